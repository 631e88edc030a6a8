"""Read prtlab archives (docs/file-format.md, docs/python.md) into numpy and scipy.

    import prtlab
    a = prtlab.read_archive("file.prt")          # kind, metadata, sections as numpy arrays
    t = prtlab.load_transfer("T.prt")            # t.matrix: scipy.sparse.csr_matrix (or a dict)
    c = prtlab.load_compressed("bicluster.prt")  # c.backend, c.metadata, c.arrays
"""

from .archive import ELEMENT_TYPES, FORMAT_VERSION, Archive, ArchiveError, read_archive
from .transfer import CompressedTransfer, Transfer, load_compressed, load_transfer
from .xxh3 import xxh3_128, xxh3_128_numpy, xxhash_available

__all__ = [
    "Archive",
    "ArchiveError",
    "CompressedTransfer",
    "ELEMENT_TYPES",
    "FORMAT_VERSION",
    "Transfer",
    "load_compressed",
    "load_transfer",
    "read_archive",
    "xxh3_128",
    "xxh3_128_numpy",
    "xxhash_available",
]
