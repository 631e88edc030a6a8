"""Builds prtlab archives byte by byte from docs/file-format.md, for the reader tests: the
reader's refusals need files a correct writer never produces (unknown element types, newer
versions, invalid CSR) but whose checksum is valid."""

import json
import struct

import numpy as np

from prtlab.archive import ELEMENT_TYPES
from prtlab.xxh3 import xxh3_128_numpy

_TAGS = {dt: tag for tag, (_, dt) in ELEMENT_TYPES.items()}


def _pad(out: bytearray) -> None:
    out += bytes(-len(out) % 16)


def meta_text(metadata: dict) -> bytes:
    """Compact JSON with sorted keys, as the C++ writer (nlohmann::json::dump) prints it."""
    return json.dumps(metadata, sort_keys=True, separators=(",", ":")).encode()


def build_archive(
    kind: str, kind_version: int, metadata: dict, sections, format_version: int = 1
) -> bytes:
    """sections: (name, array) pairs, or (name, tag, count, payload bytes) for raw records."""
    kind_b, meta_b = kind.encode(), meta_text(metadata)
    records = []
    for s in sections:
        if len(s) == 2:
            name, a = s
            a = np.ascontiguousarray(a)
            records.append(
                (
                    name,
                    _TAGS[a.dtype.newbyteorder("<")],
                    a.size,
                    a.astype(a.dtype.newbyteorder("<")).tobytes(),
                )
            )
        else:
            records.append(s)
    header_len = (40 + len(kind_b) + len(meta_b) + 15) // 16 * 16
    out = bytearray(b"PRTLAB\x00\x01")
    out += struct.pack(
        "<IIQIIII",
        format_version,
        header_len,
        0,
        kind_version,
        len(records),
        len(kind_b),
        len(meta_b),
    )
    out += kind_b + meta_b
    _pad(out)
    for name, tag, count, payload in records:
        name_b = name.encode()
        out += struct.pack("<IB3xQQ", len(name_b), tag, count, len(payload)) + name_b
        _pad(out)
        out += payload
        _pad(out)
    total = len(out) + 32
    out[16:24] = struct.pack("<Q", total)
    out += b"PRTLEND\x00" + struct.pack("<Q", total)
    out += xxh3_128_numpy(bytes(out))
    return bytes(out)
