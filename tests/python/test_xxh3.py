"""The pure-numpy XXH3-128 (python/prtlab/xxh3.py) against known digests.

The vectors were produced at development time with `xxhsum -H2` (Debian package xxhash,
0.8.1) over the inputs `pattern(n)` and `bytes(n)` below; they cover every length branch of
XXH3-128: 0, 1-3, 4-8, 9-16, 17-128, 129-240 and > 240 bytes (one stripe, partial and full
1024-byte blocks, and more blocks than one numpy chunk of the long path).
"""

import struct
import unittest

import numpy as np

from prtlab import xxh3

PATTERN_VECTORS = {
    0: "99aa06d3014798d86001c324468d497f",
    1: "a6cd5e9392000f6ac44bdff4074eecdb",
    2: "59264f999f5b71511ca5cfa6a6d57dc2",
    3: "95c705060a313bf8a1c4a8259b827291",
    4: "afbf64f9281b8de2fde8d93ae8794d8e",
    5: "a872e23fe32357632be2d19951c07993",
    7: "c64dca5a80a280cb75c20f7ea6fdec78",
    8: "2761698c33953c430234362aaf47b71a",
    9: "0d39db6431d37a74895c8a562da51412",
    10: "e3ca0a8adcb4eef110a0fec02acef053",
    15: "25bce72548003f03ebab99da883ac189",
    16: "29be75b0bbbb5284aafffcec5df2cb27",
    17: "db7e8f77961e47fd878751509ecfdb8b",
    18: "33b77de2e154291e5a2367b88c8831d6",
    31: "c7d62971fdc7cbdef165f912bffdeb23",
    32: "3e97336e6cbb6ee0de94574d7a589440",
    33: "3411cfe692c2e51ee2928442749dbe83",
    47: "cbe83b4d84c57a7c20323f621b74668a",
    48: "3bd6de116648e9bde5a81a5dfeaca691",
    63: "7799ae11f05a258afb05e0b272e66ddf",
    64: "492893316886558766fa129223be93a5",
    65: "b6dfa5aac5c63dc2f5b4ade8de9a76a3",
    80: "656a6a7f59904a6aaf7ff3e128e2b78d",
    95: "6f9e0125d27cf9bb6b5cc95aef2f7172",
    96: "e83e939b9571947cb9de9a9696c420fc",
    97: "dd6ad8d4fb1433a98ea932450271fde4",
    112: "5d4989739baf67c799bee26ccfbf3e76",
    127: "4e3b459b60f6cafa8dc4748447f5628b",
    128: "ba44fd018231af4cbbe087d879edcc78",
    129: "522c922743fd67f1b8075934107218e5",
    130: "cf90b66235522711ecd8e03310c80923",
    143: "ba6ea40f08b1c5aed6584f9669496994",
    144: "0eacd23d97d730f675d261a9d4c52479",
    159: "b8d84928ce30df2ad19ad5c36f243195",
    160: "b5514c067fd629180e08f445e497507a",
    176: "df133ade8c01584bbfeec3f2902fdaaa",
    191: "d0dbcc2422b44f19480841c9774e7cb1",
    192: "e56ca7e913690426a2ce6a625bea6b31",
    208: "ad4c72f1eca495ebf8e1d918385c493f",
    223: "1e07c71b699b493c49b740cdf2a1250c",
    224: "1979c3d65278d6b91bc08ca6847ad7bf",
    239: "c1e42329e230196f964c0b96c0e4e615",
    240: "4f49ccc8526aa7ad407883ea5ef95b9a",
    241: "50b62ee1ee6455a7bc424a2c480dd281",
    242: "f4a5d66e5a54bacf3fea34e88547cb8f",
    255: "13c4fb2eb194824f155baa5891f7606f",
    256: "20d618055259b36c2d040b1ab40f0d78",
    257: "06d2f2dce7891e45d0515fbec69efb50",
    319: "4fa135af16f380de27131b77faa0c5da",
    320: "ae31e3a96bbe40f35995107115f0890e",
    321: "bddcaf52b3a04bf9f2630d918a2b6822",
    511: "738e1d88a23cff63f3848293e35ddb39",
    512: "17d1143c4bfb7ce017ec4809d1a9ad43",
    513: "ac5683cac52a75618f6e87d203da15b7",
    1023: "d34ef4f411b9a93e3071307bafa2f8f4",
    1024: "53bd178b75ab292e1fd15e7d36f5e1bc",
    1025: "d1ad5f4a3cce4374fe08e5a874d23fd2",
    1087: "37d8d68382d6e18531bd71b326693b7f",
    1088: "9c1e8a4061056e7d0ac7cf3a6009bab5",
    1089: "76f7b4fc407270d6b246626fdf150fcb",
    2047: "02ee993d673c565700e9914a63660650",
    2048: "2e141090da5502aa81ec4a6a9ee23d55",
    2049: "3b45eb7c64d498329156a1fd2d1a8c37",
    3072: "49fe5ed15326cd5427cf4ea6f3a6d534",
    4096: "0c263f435125451084d9e7ce664c8217",
    4097: "1487c90386606b4552606c941adb173b",
    16383: "4dc58ef753d520c36ca55e84c91df594",
    16384: "9b6bf9aa8795f12f7388b93f4bfa5aee",
    16385: "af2000d482f379515946e5febebb3b4c",
    100000: "18580bb0190de1db1d43ec753d462301",
    2098152: "bdb699ed98122ece8c34ca2f0bdfe55d",
    4195329: "5cc20d5e83afbb036a3b9e8212c6e488",
}
ZEROS_VECTORS = {
    2: "4758ddac5f9ee9383325230e1f285505",
    3: "f21da334f2869f1beb5d658bb22f286b",
    4: "2a33816ed7e0c373dbe563c737220b65",
    8: "2c0a8a99dc147d5445c3b49d035665b2",
    9: "be637bf2e7ab4aec17dbb924bfd111e6",
    16: "e5189a9599e3f86205ea23ef06e28b2d",
    17: "a3d7e4cef35b1f44c2915ca0df7ad4c1",
    128: "d3c4f706d8fc547f093c29f27ecfcf21",
    129: "5dc489d54b6d88d4dd4911635f2c7a91",
    240: "0550e1dd88b6c17ca499f0a80fd3850a",
    241: "b9b45065a364c5b95c5b5d5d40c59ce3",
    1024: "0717191e67688313de5f15ab6daf7941",
    1025: "29e523d2db09ee9d64ace6654784c523",
    5000: "4f64c6c36836832295929931b75a6d9f",
}

# docs/file-format.md, "Worked example": 192 bytes and the digest pinned by
# tests/core/archive_test.cpp (Archive.ByteLayoutIsTheDocumentedOne).
DOC_EXAMPLE_DIGEST = "226245c66bed3eaf41a647e6f8d9150a"


def pattern(n: int) -> bytes:
    i = np.arange(n, dtype=np.uint64)
    return (
        (((i * np.uint64(2654435761)) & np.uint64(0xFFFFFFFF)) >> np.uint64(13))
        .astype(np.uint8)
        .tobytes()
    )


def doc_example_bytes() -> bytes:
    """The worked example of docs/file-format.md, built from the document's tables."""
    kind, meta = b"transfer-matrix", b'{"scene":"tiny"}'
    out = bytearray(b"PRTLAB\x00\x01")
    out += struct.pack("<IIQIIII", 1, 80, 208, 7, 2, len(kind), len(meta))
    out += kind + meta
    out += bytes(80 - len(out))
    out += struct.pack("<IB3xQQ", 4, 5, 3, 12) + b"cols" + bytes(112 - 80 - 28)
    out += struct.pack("<3I", 1, 2, 3) + bytes(4)
    out += struct.pack("<IB3xQQ", 6, 9, 2, 8) + b"values" + bytes(160 - 128 - 30)
    out += struct.pack("<2f", 0.25, 0.5) + bytes(8)
    out += b"PRTLEND\x00" + struct.pack("<Q", 208)
    assert len(out) == 192
    return bytes(out)


class NumpyXxh3(unittest.TestCase):
    def check(self, vectors, make):
        for n, digest in vectors.items():
            with self.subTest(length=n):
                self.assertEqual(xxh3.xxh3_128_numpy(make(n)).hex(), digest)

    def test_pattern_vectors_every_length_branch(self):
        self.check(PATTERN_VECTORS, pattern)

    def test_zero_inputs(self):
        self.check(ZEROS_VECTORS, bytes)

    def test_documented_example(self):
        self.assertEqual(xxh3.xxh3_128_numpy(doc_example_bytes()).hex(), DOC_EXAMPLE_DIGEST)

    def test_input_kinds_agree(self):
        # bytes, bytearray, memoryview, numpy uint8 and a wider-typed array of the same bytes.
        data = pattern(5000)
        expected = xxh3.xxh3_128_numpy(data)
        for obj in (
            bytearray(data),
            memoryview(data),
            np.frombuffer(data, np.uint8),
            np.frombuffer(data, "<u4"),
        ):
            self.assertEqual(xxh3.xxh3_128_numpy(obj), expected)

    def test_an_unaligned_view_hashes_like_a_copy(self):
        buf = np.frombuffer(pattern(4096 + 3), np.uint8)[3:]
        self.assertEqual(xxh3.xxh3_128_numpy(buf), xxh3.xxh3_128_numpy(buf.tobytes()))

    def test_single_bit_flips_change_the_digest(self):
        data = bytearray(pattern(3000))
        base = xxh3.xxh3_128_numpy(data)
        for pos in (0, 1, 63, 64, 1023, 1024, 2999):
            flipped = bytearray(data)
            flipped[pos] ^= 0x10
            self.assertNotEqual(xxh3.xxh3_128_numpy(flipped), base, pos)


class Dispatch(unittest.TestCase):
    def test_forced_numpy_path(self):
        for n in (0, 17, 241, 4097):
            self.assertEqual(xxh3.xxh3_128(pattern(n), "numpy").hex(), PATTERN_VECTORS[n])

    def test_unknown_implementation_is_refused(self):
        with self.assertRaises(ValueError):
            xxh3.xxh3_128(b"", "md5")

    @unittest.skipUnless(xxh3.xxhash_available(), "the xxhash module is not installed")
    def test_xxhash_module_agrees_with_numpy(self):
        rng = np.random.default_rng(7)
        for n in list(range(0, 300)) + [1023, 1024, 1025, 4096, 70001]:
            data = rng.integers(0, 256, n, dtype=np.uint8)
            self.assertEqual(xxh3.xxh3_128(data, "xxhash"), xxh3.xxh3_128_numpy(data), n)


if __name__ == "__main__":
    unittest.main()
