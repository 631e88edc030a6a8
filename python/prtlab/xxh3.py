"""XXH3-128 (seed 0), the checksum of every prtlab archive (docs/file-format.md).

`xxh3_128(data)` returns the 16 canonical bytes (high 64 bits first, big-endian: the 32 hex
digits `xxhsum -H2` prints). It uses the `xxhash` module when it is importable and otherwise
`xxh3_128_numpy`, a transcription of the scalar path of the reference xxhash.h (v0.8) with
the long-input stripe accumulation vectorised in numpy.

Why the long path vectorises: within one 1024-byte block the 16 stripe accumulations are
plain additions modulo 2^64, so all stripes of many blocks are summed at once; only the
scramble between blocks (a non-linear lane-wise step) runs block by block, on 8 lanes.
Short inputs (<= 240 bytes) are hashed with Python integers, masked to 64 bits.
"""

from __future__ import annotations

import numpy as np

try:  # the C implementation, when present, is much faster than the numpy path
    import xxhash as _xxhash
except ImportError:  # pragma: no cover - depends on the machine
    _xxhash = None

__all__ = ["xxh3_128", "xxh3_128_numpy", "xxhash_available"]

_M64 = (1 << 64) - 1
_P32_1 = 0x9E3779B1
_P32_2 = 0x85EBCA77
_P32_3 = 0xC2B2AE3D
_P64_1 = 0x9E3779B185EBCA87
_P64_2 = 0xC2B2AE3D27D4EB4F
_P64_3 = 0x165667B19E3779F9
_P64_4 = 0x85EBCA77C2B2AE63
_P64_5 = 0x27D4EB2F165667C5

_SECRET = bytes.fromhex(
    "b8fe6c3923a44bbe7c01812cf721ad1cded46de9839097db7240a4a4b7b3671f"
    "cb79e64eccc0e578825ad07dccff7221b8084674f743248ee03590e6813a264c"
    "3c2852bb91c300cb88d0658b1b532ea371644897a20df94e3819ef46a9deacd8"
    "a8fa763fe39c343ff9dcbbc7c70b4f1d8a51e04bcdb45931c89f7ec9d9787364"
    "eac5ac8334d3ebc3c581a0fffa1363eb170ddd51b7f0da49d316552629d4689e"
    "2b16be587d47a1fc8ff8b8d17ad031ce45cb3a8f95160428afd7fbcabb4b407e"
)
_SECRET_SIZE = len(_SECRET)  # 192
_SECRET_SIZE_MIN = 136
_STRIPE_LEN = 64
_SECRET_CONSUME_RATE = 8
_STRIPES_PER_BLOCK = (_SECRET_SIZE - _STRIPE_LEN) // _SECRET_CONSUME_RATE  # 16
_BLOCK_LEN = _STRIPE_LEN * _STRIPES_PER_BLOCK  # 1024
_MIDSIZE_MAX = 240
_MIDSIZE_STARTOFFSET = 3
_MIDSIZE_LASTOFFSET = 17
_SECRET_LASTACC_START = 7
_SECRET_MERGEACCS_START = 11
_INIT_ACC = (_P32_3, _P64_1, _P64_2, _P64_3, _P64_4, _P32_2, _P64_5, _P32_1)

# Blocks hashed per numpy step: bounds the temporaries (about 6 arrays of this many KiB).
_BLOCKS_PER_CHUNK = 2048


def xxhash_available() -> bool:
    return _xxhash is not None


def _r32(b, off: int) -> int:
    return int.from_bytes(b[off : off + 4], "little")


def _r64(b, off: int) -> int:
    return int.from_bytes(b[off : off + 8], "little")


def _swap32(x: int) -> int:
    return int.from_bytes(x.to_bytes(4, "little"), "big")


def _swap64(x: int) -> int:
    return int.from_bytes(x.to_bytes(8, "little"), "big")


def _rotl32(x: int, r: int) -> int:
    return ((x << r) | (x >> (32 - r))) & 0xFFFFFFFF


def _mul128(a: int, b: int) -> tuple[int, int]:
    """(low64, high64) of the 128-bit product."""
    p = a * b
    return p & _M64, p >> 64


def _mul128_fold64(a: int, b: int) -> int:
    lo, hi = _mul128(a, b)
    return lo ^ hi


def _xxh64_avalanche(h: int) -> int:
    h ^= h >> 33
    h = (h * _P64_2) & _M64
    h ^= h >> 29
    h = (h * _P64_3) & _M64
    h ^= h >> 32
    return h


def _xxh3_avalanche(h: int) -> int:
    h ^= h >> 37
    h = (h * 0x165667919E3779F9) & _M64
    h ^= h >> 32
    return h


def _mix16(b, off: int, soff: int, seed: int) -> int:
    lo = _r64(b, off) ^ ((_r64(_SECRET, soff) + seed) & _M64)
    hi = _r64(b, off + 8) ^ ((_r64(_SECRET, soff + 8) - seed) & _M64)
    return _mul128_fold64(lo, hi)


def _mix32(acc_lo: int, acc_hi: int, b, off1: int, off2: int, soff: int, seed: int):
    acc_lo = (acc_lo + _mix16(b, off1, soff, seed)) & _M64
    acc_lo ^= (_r64(b, off2) + _r64(b, off2 + 8)) & _M64
    acc_hi = (acc_hi + _mix16(b, off2, soff + 16, seed)) & _M64
    acc_hi ^= (_r64(b, off1) + _r64(b, off1 + 8)) & _M64
    return acc_lo, acc_hi


def _len_0to16(b, n: int) -> tuple[int, int]:
    if n > 8:
        bitflipl = _r64(_SECRET, 32) ^ _r64(_SECRET, 40)
        bitfliph = _r64(_SECRET, 48) ^ _r64(_SECRET, 56)
        input_lo = _r64(b, 0)
        input_hi = _r64(b, n - 8)
        lo, hi = _mul128(input_lo ^ input_hi ^ bitflipl, _P64_1)
        lo = (lo + ((n - 1) << 54)) & _M64
        input_hi ^= bitfliph
        hi = (hi + input_hi + (input_hi & 0xFFFFFFFF) * (_P32_2 - 1)) & _M64
        lo ^= _swap64(hi)
        h_lo, h_hi = _mul128(lo, _P64_2)
        h_hi = (h_hi + hi * _P64_2) & _M64
        return _xxh3_avalanche(h_lo), _xxh3_avalanche(h_hi)
    if n >= 4:
        input_64 = _r32(b, 0) + (_r32(b, n - 4) << 32)
        bitflip = _r64(_SECRET, 16) ^ _r64(_SECRET, 24)
        lo, hi = _mul128(input_64 ^ bitflip, _P64_1 + (n << 2))
        hi = (hi + (lo << 1)) & _M64
        lo ^= hi >> 3
        lo ^= lo >> 35
        lo = (lo * 0x9FB21C651E98DF25) & _M64
        lo ^= lo >> 28
        return lo, _xxh3_avalanche(hi)
    if n > 0:
        c1, c2, c3 = b[0], b[n >> 1], b[n - 1]
        combinedl = (c1 << 16) | (c2 << 24) | c3 | (n << 8)
        combinedh = _rotl32(_swap32(combinedl), 13)
        bitflipl = _r32(_SECRET, 0) ^ _r32(_SECRET, 4)
        bitfliph = _r32(_SECRET, 8) ^ _r32(_SECRET, 12)
        return _xxh64_avalanche(combinedl ^ bitflipl), _xxh64_avalanche(combinedh ^ bitfliph)
    bitflipl = _r64(_SECRET, 64) ^ _r64(_SECRET, 72)
    bitfliph = _r64(_SECRET, 80) ^ _r64(_SECRET, 88)
    return _xxh64_avalanche(bitflipl), _xxh64_avalanche(bitfliph)


def _finish_mid(acc_lo: int, acc_hi: int, n: int) -> tuple[int, int]:
    lo = (acc_lo + acc_hi) & _M64
    hi = (acc_lo * _P64_1 + acc_hi * _P64_4 + n * _P64_2) & _M64
    return _xxh3_avalanche(lo), (-_xxh3_avalanche(hi)) & _M64


def _len_17to128(b, n: int) -> tuple[int, int]:
    acc_lo, acc_hi = (n * _P64_1) & _M64, 0
    if n > 32:
        if n > 64:
            if n > 96:
                acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, 48, n - 64, 96, 0)
            acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, 32, n - 48, 64, 0)
        acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, 16, n - 32, 32, 0)
    acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, 0, n - 16, 0, 0)
    return _finish_mid(acc_lo, acc_hi, n)


def _len_129to240(b, n: int) -> tuple[int, int]:
    acc_lo, acc_hi = (n * _P64_1) & _M64, 0
    for i in range(4):
        acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, 32 * i, 32 * i + 16, 32 * i, 0)
    acc_lo, acc_hi = _xxh3_avalanche(acc_lo), _xxh3_avalanche(acc_hi)
    for i in range(4, n // 32):
        soff = _MIDSIZE_STARTOFFSET + 32 * (i - 4)
        acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, 32 * i, 32 * i + 16, soff, 0)
    soff = _SECRET_SIZE_MIN - _MIDSIZE_LASTOFFSET - 16
    acc_lo, acc_hi = _mix32(acc_lo, acc_hi, b, n - 16, n - 32, soff, 0)
    return _finish_mid(acc_lo, acc_hi, n)


def _secret_words(offset: int, count: int) -> np.ndarray:
    return np.frombuffer(_SECRET, dtype="<u8", count=count, offset=offset).astype(np.uint64)


# Stripe s of a block reads the 8 secret words starting at byte 8 s.
_STRIPE_KEYS = np.stack(
    [_secret_words(_SECRET_CONSUME_RATE * s, 8) for s in range(_STRIPES_PER_BLOCK)]
)
_SCRAMBLE_KEY = _secret_words(_SECRET_SIZE - _STRIPE_LEN, 8)
_LAST_STRIPE_KEY = _secret_words(_SECRET_SIZE - _STRIPE_LEN - _SECRET_LASTACC_START, 8)
# Lane i's input is also added to lane i ^ 1.
_LANE_SWAP = np.array([1, 0, 3, 2, 5, 4, 7, 6])
_LO32 = np.uint64(0xFFFFFFFF)
_SHIFT32 = np.uint64(32)
_SHIFT47 = np.uint64(47)
_PRIME32_1 = np.uint64(_P32_1)


def _stripe_sums(words: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Sum over axis -2 (stripes) of the accumulate step, for words (..., stripes, 8)."""
    data_key = words ^ keys
    product = (data_key & _LO32) * (data_key >> _SHIFT32)
    return (
        product.sum(axis=-2, dtype=np.uint64) + words.sum(axis=-2, dtype=np.uint64)[..., _LANE_SWAP]
    )


def _scramble(acc: np.ndarray) -> np.ndarray:
    return ((acc ^ (acc >> _SHIFT47)) ^ _SCRAMBLE_KEY) * _PRIME32_1


def _merge_accs(acc: list[int], soff: int, start: int) -> int:
    result = start
    for i in range(4):
        result += _mul128_fold64(
            acc[2 * i] ^ _r64(_SECRET, soff + 16 * i),
            acc[2 * i + 1] ^ _r64(_SECRET, soff + 16 * i + 8),
        )
    return _xxh3_avalanche(result & _M64)


def _as_u8(data) -> np.ndarray:
    if isinstance(data, np.ndarray):
        return data.reshape(-1).view(np.uint8)
    return np.frombuffer(memoryview(data).cast("B"), dtype=np.uint8)


def _hash_long(u8: np.ndarray) -> tuple[int, int]:
    n = u8.size
    nb_blocks = (n - 1) // _BLOCK_LEN
    acc = np.array(_INIT_ACC, dtype=np.uint64)
    with np.errstate(over="ignore"):
        for first in range(0, nb_blocks, _BLOCKS_PER_CHUNK):
            count = min(_BLOCKS_PER_CHUNK, nb_blocks - first)
            chunk = u8[first * _BLOCK_LEN : (first + count) * _BLOCK_LEN]
            words = np.frombuffer(chunk, dtype="<u8").reshape(count, _STRIPES_PER_BLOCK, 8)
            sums = _stripe_sums(words.astype(np.uint64, copy=False), _STRIPE_KEYS)
            for block in sums:
                acc = _scramble(acc + block)
        tail_start = nb_blocks * _BLOCK_LEN
        stripes = ((n - 1) - tail_start) // _STRIPE_LEN
        if stripes:
            tail = u8[tail_start : tail_start + stripes * _STRIPE_LEN]
            words = np.frombuffer(tail, dtype="<u8").reshape(stripes, 8).astype(np.uint64)
            acc = acc + _stripe_sums(words, _STRIPE_KEYS[:stripes])
        last = np.frombuffer(u8[n - _STRIPE_LEN :], dtype="<u8").reshape(1, 8).astype(np.uint64)
        acc = acc + _stripe_sums(last, _LAST_STRIPE_KEY)
    lanes = [int(x) for x in acc]
    lo = _merge_accs(lanes, _SECRET_MERGEACCS_START, (n * _P64_1) & _M64)
    hi = _merge_accs(
        lanes, _SECRET_SIZE - _STRIPE_LEN - _SECRET_MERGEACCS_START, ~(n * _P64_2) & _M64
    )
    return lo, hi


def xxh3_128_numpy(data) -> bytes:
    """XXH3-128 with seed 0 of a bytes-like object or numpy array, in numpy only."""
    u8 = _as_u8(data)
    n = u8.size
    if n <= 16:
        lo, hi = _len_0to16(u8.tobytes(), n)
    elif n <= 128:
        lo, hi = _len_17to128(u8.tobytes(), n)
    elif n <= _MIDSIZE_MAX:
        lo, hi = _len_129to240(u8.tobytes(), n)
    else:
        lo, hi = _hash_long(u8)
    return hi.to_bytes(8, "big") + lo.to_bytes(8, "big")


def xxh3_128(data, implementation: str | None = None) -> bytes:
    """XXH3-128 (seed 0), canonical 16 bytes. implementation: None (the `xxhash` module when
    importable, else numpy), "xxhash" or "numpy"."""
    if implementation is None:
        implementation = "xxhash" if _xxhash is not None else "numpy"
    if implementation == "numpy":
        return xxh3_128_numpy(data)
    if implementation == "xxhash":
        if _xxhash is None:
            raise RuntimeError("the xxhash module is not installed (python3-xxhash)")
        return _xxhash.xxh3_128(_as_u8(data)).digest()
    raise ValueError(f"unknown XXH3 implementation '{implementation}' (xxhash, numpy)")
