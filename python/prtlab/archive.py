"""Reading prtlab archives (docs/file-format.md) into numpy.

`read_archive(path)` maps the file, verifies its length and XXH3-128 checksum before it
parses anything, and returns an `Archive` whose sections are little-endian numpy arrays
viewing the mapped file (read-only; `np.array(a)` copies). It refuses exactly what the C++
`ArchiveReader::open` refuses, in the same order and with the same wording, as an
`ArchiveError` whose message starts with the file name.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from .xxh3 import xxh3_128

__all__ = ["Archive", "ArchiveError", "read_archive", "ELEMENT_TYPES", "FORMAT_VERSION"]

FORMAT_VERSION = 1

_MAGIC = b"PRTLAB\x00\x01"
_END_MAGIC = b"PRTLEND\x00"
_FIXED_HEADER_BYTES = 40
_SECTION_RECORD_BYTES = 24
_TRAILER_BYTES = 32
_CHECKSUM_BYTES = 16
_ALIGN = 16
_MAX_NAME_BYTES = 255
# Fixed header, a 1-byte kind and "{}", padded to 16, then the trailer.
_MIN_ARCHIVE_BYTES = 48 + _TRAILER_BYTES

# Element type tag -> (name, little-endian numpy dtype).
ELEMENT_TYPES = {
    1: ("uint8", np.dtype("<u1")),
    2: ("int8", np.dtype("<i1")),
    3: ("uint16", np.dtype("<u2")),
    4: ("int16", np.dtype("<i2")),
    5: ("uint32", np.dtype("<u4")),
    6: ("int32", np.dtype("<i4")),
    7: ("uint64", np.dtype("<u8")),
    8: ("int64", np.dtype("<i8")),
    9: ("float32", np.dtype("<f4")),
    10: ("float64", np.dtype("<f8")),
}


class ArchiveError(ValueError):
    """A file that is not a usable prtlab archive; str() is '<file>: <problem>'."""

    def __init__(self, path, problem: str):
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


@dataclass
class Archive:
    path: str
    format_version: int
    kind: str
    kind_version: int
    metadata: dict
    sections: dict = field(default_factory=dict)  # name -> np.ndarray, in file order
    checksum: str = ""  # 32 hex digits, as `xxhsum -H2` prints them

    def expect_kind(self, kind: str, max_kind_version: int | None = None) -> None:
        """Refuses another kind or a newer kind version, as ArchiveReader::expect_kind."""
        if kind and kind != self.kind:
            raise ArchiveError(self.path, f"artifact kind is '{self.kind}', expected '{kind}'")
        if max_kind_version is not None and self.kind_version > max_kind_version:
            raise ArchiveError(
                self.path,
                f"'{self.kind}' version {self.kind_version} is newer than this reader "
                f"supports ({max_kind_version}); update prtlab or delete the file",
            )

    def section(self, name: str, dtype=None, count: int | None = None) -> np.ndarray:
        """The named section, checked for its stored type and element count when given."""
        if name not in self.sections:
            present = ", ".join(self.sections) or "none"
            raise ArchiveError(self.path, f"section '{name}' missing (sections present: {present})")
        a = self.sections[name]
        if dtype is not None and np.dtype(dtype).newbyteorder("<") != a.dtype:
            raise ArchiveError(
                self.path,
                f"section '{name}' holds {_type_name(a.dtype)} but {_type_name(np.dtype(dtype))} "
                "was requested",
            )
        if count is not None and a.size != count:
            raise ArchiveError(
                self.path, f"section '{name}' has {a.size} elements, expected {count}"
            )
        return a

    def indices(self, name: str, count: int | None = None) -> np.ndarray:
        """An index section stored as u16 or u32 (ArchiveReader::indices), as uint32."""
        a = self.section(name, count=count)
        if a.dtype not in (np.dtype("<u2"), np.dtype("<u4")):
            raise ArchiveError(
                self.path,
                f"section '{name}' holds {_type_name(a.dtype)}, expected uint16 or uint32",
            )
        return a.astype(np.uint32)

    def meta(self, key: str, kind=None):
        """A metadata value, checked to be an instance of `kind` when given."""
        if key not in self.metadata:
            raise ArchiveError(self.path, f"metadata key '{key}' missing")
        v = self.metadata[key]
        if kind is not None and (not isinstance(v, kind) or (kind is int and isinstance(v, bool))):
            raise ArchiveError(
                self.path, f"metadata key '{key}' has the wrong type ({json.dumps(v)[:80]})"
            )
        return v


def _type_name(dtype: np.dtype) -> str:
    for name, dt in ELEMENT_TYPES.values():
        if dt == dtype:
            return name
    return str(dtype)


def _align(x: int) -> int:
    return (x + _ALIGN - 1) & ~(_ALIGN - 1)


def _u32(d: np.ndarray, off: int) -> int:
    return int.from_bytes(d[off : off + 4].tobytes(), "little")


def _u64(d: np.ndarray, off: int) -> int:
    return int.from_bytes(d[off : off + 8].tobytes(), "little")


def _map(path: str) -> np.ndarray:
    try:
        if os.path.isdir(path):
            raise ArchiveError(path, "is a directory, not an archive")
        size = os.path.getsize(path)
        if size == 0:
            with open(path, "rb"):
                pass
            return np.zeros(0, dtype=np.uint8)
        return np.memmap(path, dtype=np.uint8, mode="r")
    except OSError as e:
        raise ArchiveError(path, f"cannot open: {e.strerror or e}") from None


def read_archive(
    path, expected_kind: str = "", max_kind_version: int | None = None, xxh3: str | None = None
) -> Archive:
    """Open and verify a prtlab archive.

    expected_kind / max_kind_version: refuse another artifact kind or a newer kind version.
    xxh3: the checksum implementation (None: the `xxhash` module when importable, else numpy;
    "xxhash"; "numpy").
    """
    path = os.fspath(path)
    d = _map(path)
    m = d.size

    def refuse(problem: str):
        return ArchiveError(path, problem)

    def malformed(what: str):
        return ArchiveError(path, f"malformed archive (file corrupt): {what}")

    # 1. Envelope: magic, then length, then checksum; nothing else is trusted before that.
    if m == 0:
        raise refuse("empty file (not a prtlab archive)")
    if d[: min(m, len(_MAGIC))].tobytes() != _MAGIC[: min(m, len(_MAGIC))]:
        raise refuse("not a prtlab archive (it does not start with the PRTLAB magic)")
    if m < 24:
        raise refuse(
            f"truncated: file has {m} bytes, the smallest archive has {_MIN_ARCHIVE_BYTES}"
        )
    length = _u64(d, 16)

    def trailer_fits(end: int) -> bool:
        return (
            _MIN_ARCHIVE_BYTES <= end <= m
            and d[end - _TRAILER_BYTES : end - _TRAILER_BYTES + 8].tobytes() == _END_MAGIC
            and _u64(d, end - _TRAILER_BYTES + 8) == end
        )

    if length != m:
        # A complete trailer at the end of the file means the length in the header was damaged.
        if trailer_fits(m):
            raise refuse("checksum mismatch (file corrupt)")
        if length > m:
            raise refuse(f"truncated: expected {length} bytes, file has {m}")
        if trailer_fits(length):
            raise refuse(
                f"{m - length} bytes of unexpected data after the end of the archive "
                f"(expected {length} bytes, file has {m})"
            )
        raise refuse("checksum mismatch (file corrupt)")
    if m < _MIN_ARCHIVE_BYTES:
        raise refuse(
            f"truncated: file has {m} bytes, the smallest archive has {_MIN_ARCHIVE_BYTES}"
        )
    checked = m - _CHECKSUM_BYTES
    stored = d[checked:].tobytes()
    if xxh3_128(d[:checked], xxh3) != stored:
        raise refuse("checksum mismatch (file corrupt)")
    if not trailer_fits(m):
        raise malformed("bad trailer")

    # 2. Versions.
    format_version = _u32(d, 8)
    if format_version > FORMAT_VERSION:
        raise refuse(
            f"format version {format_version} is newer than this reader supports "
            f"({FORMAT_VERSION}); update prtlab or delete the file"
        )
    if format_version == 0:
        raise malformed("format version 0")

    # 3. Header.
    end = m - _TRAILER_BYTES
    header_bytes = _u32(d, 12)
    kind_version = _u32(d, 24)
    section_count = _u32(d, 28)
    kind_bytes = _u32(d, 32)
    meta_bytes = _u32(d, 36)
    if (
        header_bytes % _ALIGN != 0
        or header_bytes > end
        or _FIXED_HEADER_BYTES + kind_bytes + meta_bytes > header_bytes
    ):
        raise malformed(f"header length {header_bytes} does not fit")
    if kind_bytes == 0 or kind_bytes > _MAX_NAME_BYTES:
        raise malformed("bad artifact kind length")
    try:
        kind = d[_FIXED_HEADER_BYTES : _FIXED_HEADER_BYTES + kind_bytes].tobytes().decode("utf-8")
    except UnicodeDecodeError:
        raise malformed("artifact kind is not UTF-8") from None
    meta_start = _FIXED_HEADER_BYTES + kind_bytes
    try:
        metadata = json.loads(d[meta_start : meta_start + meta_bytes].tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise malformed(f"metadata is not valid JSON ({e})") from None
    if not isinstance(metadata, dict):
        raise malformed("metadata is not a JSON object")

    # 4. Sections.
    sections: dict = {}
    off = header_bytes
    if section_count > (end - header_bytes) // _SECTION_RECORD_BYTES:
        raise malformed(f"{section_count} sections cannot fit in the file")
    for i in range(section_count):
        if end - off < _SECTION_RECORD_BYTES:
            raise malformed(f"section {i} runs past the end")
        name_bytes = _u32(d, off)
        tag = int(d[off + 4])
        count = _u64(d, off + 8)
        nbytes = _u64(d, off + 16)
        if (
            name_bytes == 0
            or name_bytes > _MAX_NAME_BYTES
            or end - off - _SECTION_RECORD_BYTES < name_bytes
        ):
            raise malformed(f"section {i} has a bad name length {name_bytes}")
        raw_name = d[
            off + _SECTION_RECORD_BYTES : off + _SECTION_RECORD_BYTES + name_bytes
        ].tobytes()
        name = raw_name.decode("utf-8", errors="replace")
        if tag not in ELEMENT_TYPES:
            raise malformed(f"section '{name}' has unknown element type {tag}")
        type_name, dtype = ELEMENT_TYPES[tag]
        if nbytes % dtype.itemsize != 0 or nbytes // dtype.itemsize != count:
            raise malformed(
                f"section '{name}' holds {nbytes} bytes, not {count} {type_name} elements"
            )
        payload = _align(off + _SECTION_RECORD_BYTES + name_bytes)
        if payload > end or end - payload < nbytes:
            raise malformed(f"section '{name}' runs past the end")
        if name in sections:
            raise malformed(f"section '{name}' appears twice")
        sections[name] = d[payload : payload + nbytes].view(dtype)
        off = _align(payload + nbytes)
    if off != end:
        raise malformed(f"{end - off} unexpected bytes after the last section")

    archive = Archive(
        path=str(path),
        format_version=format_version,
        kind=kind,
        kind_version=kind_version,
        metadata=metadata,
        sections=sections,
        checksum=stored.hex(),
    )
    archive.expect_kind(expected_kind, max_kind_version)
    return archive
