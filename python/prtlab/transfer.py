"""The transfer matrix T and compressed transfers, from their prtlab archives.

T (kind `transfer-matrix`, core/include/prtlab/transfer/transfer_io.h) is (vertices * M) x N,
row `vertex * M + j`, stored as CSR with u32 row offsets, u16 or u32 columns and u8 counts c
in 1..s^2; an entry's value is c / s^2. `load_transfer` checks the same CSR invariants as the
C++ loader (TransferMatrix::from_csr) and returns T as a `scipy.sparse.csr_matrix` when scipy
is importable, else as a dict of the CSR arrays.

A compressed transfer (kind `compressed-transfer`) holds whatever its backend's save()
wrote; `load_compressed` returns the backend name, the metadata and the named arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .archive import Archive, ArchiveError, read_archive

__all__ = [
    "Transfer",
    "CompressedTransfer",
    "load_transfer",
    "load_compressed",
    "TRANSFER_KIND",
    "COMPRESSED_KIND",
]

TRANSFER_KIND = "transfer-matrix"
TRANSFER_KIND_VERSION = 1
COMPRESSED_KIND = "compressed-transfer"
COMPRESSED_KIND_VERSION = 1

# Entries checked per numpy step in the CSR validation.
_CHECK_CHUNK_ENTRIES = 1 << 22

try:
    import scipy.sparse as _sparse
except ImportError:  # pragma: no cover - depends on the machine
    _sparse = None


@dataclass
class Transfer:
    matrix: object  # scipy.sparse.csr_matrix, or dict(indptr, indices, data, shape)
    vertices: int
    local_count: int  # M = S^2
    pixel_count: int  # N = 6 R^2
    supersampling: int  # s: values are counts / s^2
    counts: np.ndarray  # u8 counts, one per stored entry (the exact values)
    sh: np.ndarray | None  # (vertices, n^2, n^2) float64 SH transfer, when stored
    metadata: dict = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.vertices * self.local_count, self.pixel_count)

    @property
    def nnz(self) -> int:
        return int(self.counts.size)

    @property
    def scale(self) -> float:
        """Value of a count of 1 (1 / s^2)."""
        return 1.0 / (float(self.supersampling) * self.supersampling)


@dataclass
class CompressedTransfer:
    backend: str
    metadata: dict
    arrays: dict  # section name -> np.ndarray, in file order
    flops_per_relight: float  # one colour channel, a multiply-add counted as 2
    storage_bytes: int


def _open(source, kind: str, version: int, xxh3: str | None) -> Archive:
    if isinstance(source, Archive):
        source.expect_kind(kind, version)
        return source
    return read_archive(source, kind, version, xxh3=xxh3)


def _check_csr(a: Archive, rows: int, m: int, n: int, s: int, offsets, columns, counts) -> None:
    """TransferMatrix::from_csr's invariants, vectorised; violations name the file."""

    def invalid(what: str):
        return ArchiveError(a.path, f"invalid transfer matrix: {what}")

    nnz = counts.size
    if offsets.size != rows + 1:
        raise invalid(f"{offsets.size} row offsets for {rows} rows (expected {rows + 1})")
    if columns.size != nnz:
        raise invalid(f"{columns.size} column indices for {nnz} counts")
    if offsets[0] != 0 or int(offsets[-1]) != nnz:
        raise invalid(f"row offsets run from {offsets[0]} to {offsets[-1]}, expected 0 to {nnz}")
    if np.any(np.diff(offsets.astype(np.int64)) < 0):
        raise invalid("row offsets decrease")
    if nnz == 0:
        return
    if int(columns.max()) >= n:
        raise invalid(f"a column index is >= N = {n}")
    if int(counts.min()) < 1 or int(counts.max()) > s * s:
        raise invalid(f"a count is outside 1..s^2 = {s * s}")
    # Strictly increasing columns in a row, and no column twice in a vertex block: checked
    # over runs of whole vertex blocks, so the temporaries stay small for any nnz.
    vertices = rows // m
    block_starts = offsets[::m].astype(np.int64)  # vertices + 1 entries
    first = 0
    while first < vertices:
        begin = int(block_starts[first])
        last = int(np.searchsorted(block_starts, begin + _CHECK_CHUNK_ENTRIES, side="right")) - 1
        last = min(vertices, max(first + 1, last))
        stop = int(block_starts[last])
        lengths = np.diff(offsets[first * m : last * m + 1].astype(np.int64))
        row_of = np.repeat(np.arange(lengths.size, dtype=np.int64), lengths)
        cols = columns[begin:stop].astype(np.int64)
        if np.any((row_of[1:] == row_of[:-1]) & (cols[1:] <= cols[:-1])):
            raise invalid("columns are not strictly increasing within a row")
        keys = np.sort((row_of // m) * n + cols)
        if np.any(keys[1:] == keys[:-1]):
            raise invalid("a column holds two entries in one vertex block")
        first = last


def load_transfer(
    source, dtype=np.float32, as_scipy: bool | None = None, xxh3: str | None = None
) -> Transfer:
    """T from a `transfer-matrix` archive (a path, e.g. a stage-cache entry
    `$PRTLAB_CACHE/transfer/<key>.prt`, or an Archive).

    dtype: float32 (the C++ TransferMatrix::value(): float(c * (1 / s^2))) or float64 (c / s^2).
    as_scipy: None gives a csr_matrix when scipy is importable, else the dict; True / False
    force one (True without scipy raises ImportError).
    """
    a = _open(source, TRANSFER_KIND, TRANSFER_KIND_VERSION, xxh3)
    vertices = a.meta("vertices", int)
    m = a.meta("local_count", int)
    n = a.meta("pixel_count", int)
    s = a.meta("supersampling", int)
    sh_order = a.meta("sh_order", int)
    if vertices < 0 or m <= 0 or n <= 0 or s <= 0:
        raise ArchiveError(a.path, "invalid transfer matrix: bad shape in the metadata")
    rows = vertices * m
    offsets = a.section("row_offsets", np.uint32)
    columns = a.indices("columns")
    counts = a.section("counts", np.uint8)
    _check_csr(a, rows, m, n, s, offsets, columns, counts)
    return _assemble(a, vertices, m, n, s, sh_order, offsets, columns, counts, dtype, as_scipy)


def _values(counts: np.ndarray, s: int, dtype) -> np.ndarray:
    dtype = np.dtype(dtype)
    if dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise ValueError(f"dtype must be float32 or float64, not {dtype}")
    # As the C++: the count times the double scale 1 / s^2, then rounded once to the dtype.
    return (counts.astype(np.float64) * (1.0 / (float(s) * s))).astype(dtype)


def _assemble(a, vertices, m, n, s, sh_order, offsets, columns, counts, dtype, as_scipy):
    data = _values(counts, s, dtype)
    rows = vertices * m
    if as_scipy is None:
        as_scipy = _sparse is not None
    if as_scipy:
        if _sparse is None:
            raise ImportError("scipy is not installed (python3-scipy); pass as_scipy=False")
        # scipy converts the u32 index arrays to int32, or int64 where the sizes need it.
        matrix = _sparse.csr_matrix((data, columns, offsets), shape=(rows, n))
    else:
        matrix = {
            "indptr": np.asarray(offsets),
            "indices": columns,
            "data": data,
            "shape": (rows, n),
        }
    sh = None
    if sh_order > 0:
        d = sh_order * sh_order
        sh = a.section("sh", np.float64, vertices * d * d).reshape(vertices, d, d)
    return Transfer(
        matrix=matrix,
        vertices=vertices,
        local_count=m,
        pixel_count=n,
        supersampling=s,
        counts=np.asarray(counts),
        sh=sh,
        metadata=a.metadata,
    )


def load_compressed(source, xxh3: str | None = None) -> CompressedTransfer:
    """A compressed transfer (`prtlab compress --save FILE`, or a stage-cache entry
    `$PRTLAB_CACHE/compressed-<backend>/<key>.prt`): backend, metadata, named arrays."""
    a = _open(source, COMPRESSED_KIND, COMPRESSED_KIND_VERSION, xxh3)
    return CompressedTransfer(
        backend=a.meta("backend", str),
        metadata=a.metadata,
        arrays=dict(a.sections),
        flops_per_relight=float(a.meta("flops_per_relight", (int, float))),
        storage_bytes=a.meta("storage_bytes", int),
    )
