"""The Python archive reader (python/prtlab) against archives the C++ writer of this build
produced: prtlab-python-fixtures' files and expected.json (the C++ reader's view of them), and
the CLI's stage cache and `compress --save` files.

Run by CTest (python_archive_reader), which sets PRTLAB_PY_FIXTURES (the fixture folder) and
PRTLAB_TEST_CLI (the prtlab-test executable).
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import numpy as np

from archive_builder import build_archive
from prtlab import ArchiveError, load_compressed, load_transfer, read_archive
from prtlab.xxh3 import xxh3_128_numpy

try:
    import scipy.sparse  # noqa: F401

    HAVE_SCIPY = True
except ImportError:
    HAVE_SCIPY = False


def fixture_dir() -> Path:
    d = os.environ.get("PRTLAB_PY_FIXTURES")
    if not d:
        raise RuntimeError(
            "PRTLAB_PY_FIXTURES is not set: run this test through ctest (python_archive_reader), "
            "or run build/release/tests/prtlab-python-fixtures DIR and set it to DIR"
        )
    return Path(d)


def setUpModule():
    global FIX, EXPECTED, TMP
    FIX = fixture_dir()
    EXPECTED = json.loads((FIX / "expected.json").read_text())
    TMP = Path(tempfile.mkdtemp(prefix="prtlab-pyreader-"))


def tearDownModule():
    shutil.rmtree(TMP, ignore_errors=True)


def digest(a: np.ndarray) -> str:
    return xxh3_128_numpy(np.ascontiguousarray(a).tobytes()).hex()


def csr_product(indptr, indices, data, light):
    """T L with numpy only (no scipy): per-entry products summed per row."""
    rows = np.repeat(np.arange(indptr.size - 1), np.diff(indptr.astype(np.int64)))
    out = np.zeros((indptr.size - 1, light.shape[1]))
    np.add.at(out, rows, data.astype(np.float64)[:, None] * light[indices])
    return out


class SameAsCppReader(unittest.TestCase):
    """Every fixture file: checksum, kind and each section's type, count and payload bytes as
    the C++ ArchiveReader saw them, through both XXH3 implementations."""

    def all_files(self):
        return EXPECTED["transfers"] + EXPECTED["compressed"] + [EXPECTED["element_types"]]

    def test_sections_match_the_cpp_reader(self):
        for e in self.all_files():
            for impl in (None, "numpy"):
                with self.subTest(file=e["file"], xxh3=impl):
                    a = read_archive(FIX / e["file"], xxh3=impl)
                    self.assertEqual(a.checksum, e["checksum"])
                    self.assertEqual(a.kind, e["kind"])
                    self.assertEqual(a.kind_version, e["kind_version"])
                    self.assertEqual(a.format_version, 1)
                    self.assertEqual(list(a.sections), [s["name"] for s in e["sections"]])
                    for s in e["sections"]:
                        arr = a.sections[s["name"]]
                        self.assertEqual(arr.dtype.name, s["type"], s["name"])
                        self.assertEqual(arr.dtype.byteorder in ("<", "|", "="), True)
                        self.assertEqual(arr.size, s["count"], s["name"])
                        self.assertEqual(digest(arr), s["xxh3"], s["name"])

    def test_checksum_is_the_xxh3_of_everything_before_it(self):
        for e in self.all_files():
            raw = (FIX / e["file"]).read_bytes()
            self.assertEqual(len(raw), e["bytes"])
            self.assertEqual(xxh3_128_numpy(raw[:-16]).hex(), e["checksum"], e["file"])

    def test_rebuilding_from_the_parsed_contents_gives_the_same_bytes(self):
        # Header, record layout, alignment and zero padding as the C++ writer emits them.
        for e in EXPECTED["compressed"] + [EXPECTED["element_types"]]:
            a = read_archive(FIX / e["file"])
            rebuilt = build_archive(a.kind, a.kind_version, a.metadata, list(a.sections.items()))
            self.assertEqual(rebuilt, (FIX / e["file"]).read_bytes(), e["file"])


class ElementTypes(unittest.TestCase):
    def test_every_type_holds_its_extremes(self):
        a = read_archive(FIX / EXPECTED["element_types"]["file"], "element-types", 3)
        s = a.sections
        self.assertEqual(a.metadata["note"], "every element type at its extremes")
        self.assertEqual(s["u8"].tolist(), [0, 1, 127, 128, 255])
        self.assertEqual(s["i8"].tolist(), [-128, -1, 0, 1, 127])
        self.assertEqual(s["u16"].tolist(), [0, 1, 0x8000, 0xFFFF])
        self.assertEqual(s["i16"].tolist(), [-32768, -1, 0, 32767])
        self.assertEqual(s["u32"].tolist(), [0, 1, 2**31, 2**32 - 1])
        self.assertEqual(s["i32"].tolist(), [-(2**31), -1, 0, 2**31 - 1])
        self.assertEqual(s["u64"].tolist(), [0, 1, 2**63, 2**64 - 1])
        self.assertEqual(s["i64"].tolist(), [-(2**63), -1, 0, 2**63 - 1])
        f32 = np.finfo(np.float32)
        self.assertEqual(
            s["f32"].view(np.uint32).tolist(),
            [0x80000000, 0x7FC00001]
            + np.array([np.inf, -np.inf, f32.smallest_subnormal, f32.max, 0.1], dtype=np.float32)
            .view(np.uint32)
            .tolist(),
        )
        f64 = np.finfo(np.float64)
        self.assertEqual(
            s["f64"].view(np.uint64).tolist(),
            [0x8000000000000000, 0x7FF8000000000001]
            + np.array([np.inf, -np.inf, f64.smallest_subnormal, f64.max, 0.1])
            .view(np.uint64)
            .tolist(),
        )
        self.assertEqual((s["empty"].dtype.name, s["empty"].size), ("float64", 0))

    def test_sections_are_read_only_views(self):
        a = read_archive(FIX / EXPECTED["element_types"]["file"])
        with self.assertRaises(ValueError):
            a.sections["u8"][0] = 1

    def test_typed_accessors(self):
        a = read_archive(FIX / EXPECTED["element_types"]["file"])
        self.assertEqual(a.section("u16", np.uint16, 4).tolist(), [0, 1, 0x8000, 0xFFFF])
        self.assertEqual(a.indices("u16").dtype, np.uint32)
        with self.assertRaisesRegex(
            ArchiveError, "section 'u16' holds uint16 but uint32 was requested"
        ):
            a.section("u16", np.uint32)
        with self.assertRaisesRegex(ArchiveError, "section 'u16' has 4 elements, expected 5"):
            a.section("u16", count=5)
        with self.assertRaisesRegex(
            ArchiveError, r"section 'nope' missing \(sections present: u8, i8"
        ):
            a.section("nope")
        with self.assertRaisesRegex(ArchiveError, "metadata key 'scene' missing"):
            a.meta("scene")


class Transfers(unittest.TestCase):
    def each(self):
        for e in EXPECTED["transfers"]:
            with self.subTest(file=e["file"]):
                yield e

    def test_shape_metadata_and_exact_values(self):
        for e in self.each():
            t = load_transfer(FIX / e["file"])
            self.assertEqual(t.shape, (e["rows"], e["pixel_count"]))
            self.assertEqual(
                (t.vertices, t.local_count, t.pixel_count, t.supersampling),
                (e["vertices"], e["local_count"], e["pixel_count"], e["supersampling"]),
            )
            self.assertEqual(t.nnz, e["nnz"])
            # float32 values bit-identical to TransferMatrix::value().
            data = t.matrix.data if HAVE_SCIPY else t.matrix["data"]
            self.assertEqual(data.dtype, np.float32)
            self.assertEqual(digest(data), e["values_float32_xxh3"])
            t64 = load_transfer(FIX / e["file"], dtype=np.float64)
            d64 = t64.matrix.data if HAVE_SCIPY else t64.matrix["data"]
            np.testing.assert_array_equal(d64, t.counts / float(t.supersampling) ** 2)
            cols = read_archive(FIX / e["file"]).sections["columns"]
            self.assertEqual(cols.dtype, np.uint16 if e["narrow_columns"] else np.uint32)

    def test_product_equals_the_cpp_double_relight(self):
        for e in self.each():
            light = np.array(e["light"], dtype=np.float64)
            expected = np.array(e["product"], dtype=np.float64).reshape(e["rows"], 3)
            t = load_transfer(FIX / e["file"], dtype=np.float64, as_scipy=False)
            m = t.matrix
            self.assertEqual(m["shape"], (e["rows"], e["pixel_count"]))
            got = csr_product(m["indptr"], m["indices"], m["data"], light)
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)
            if HAVE_SCIPY:
                t = load_transfer(FIX / e["file"], dtype=np.float64)
                self.assertEqual(t.matrix.format, "csr")
                np.testing.assert_allclose(t.matrix @ light, expected, rtol=1e-12, atol=0)
                ones = np.asarray(t.matrix.sum(axis=1)).ravel()
                np.testing.assert_allclose(
                    ones,
                    csr_product(
                        m["indptr"], m["indices"], m["data"], np.ones((e["pixel_count"], 1))
                    )[:, 0],
                )

    def test_sh_transfer(self):
        for e in self.each():
            t = load_transfer(FIX / e["file"])
            if e["sh_order"] == 0:
                self.assertIsNone(t.sh)
                continue
            d = e["sh_order"] ** 2
            self.assertEqual(t.sh.shape, (e["vertices"], d, d))
            self.assertEqual(t.sh.dtype, np.float64)
            self.assertEqual(
                digest(t.sh), next(s["xxh3"] for s in e["sections"] if s["name"] == "sh")
            )
            self.assertTrue(np.any(t.sh != 0))

    def test_dict_and_scipy_forms_hold_the_same_matrix(self):
        if not HAVE_SCIPY:
            self.skipTest("scipy is not installed: only the dict form exists")
        for e in self.each():
            a = load_transfer(FIX / e["file"]).matrix
            b = load_transfer(FIX / e["file"], as_scipy=False).matrix
            np.testing.assert_array_equal(a.indptr, b["indptr"])
            np.testing.assert_array_equal(a.indices, b["indices"])
            np.testing.assert_array_equal(a.data, b["data"])


class Compressed(unittest.TestCase):
    def test_every_backend(self):
        self.assertGreaterEqual(len(EXPECTED["compressed"]), 2)
        for e in EXPECTED["compressed"]:
            with self.subTest(backend=e["backend"]):
                c = load_compressed(FIX / e["file"])
                self.assertEqual(c.backend, e["backend"])
                self.assertEqual(c.storage_bytes, e["storage_bytes"])
                self.assertEqual(c.flops_per_relight, e["flops_per_relight"])
                self.assertEqual(list(c.arrays), [s["name"] for s in e["sections"]])

    def test_uncompressed_holds_the_transfer_arrays(self):
        e = next(c for c in EXPECTED["compressed"] if c["backend"] == "uncompressed")
        c = load_compressed(FIX / e["file"])
        t = read_archive(FIX / EXPECTED["transfers"][0]["file"])
        for name in ("row_offsets", "columns", "counts"):
            np.testing.assert_array_equal(c.arrays[name], t.sections[name])
            self.assertEqual(c.arrays[name].dtype, t.sections[name].dtype)


class Refusals(unittest.TestCase):
    """The C++ reader's refusals (docs/file-format.md, "Verification order")."""

    @classmethod
    def setUpClass(cls):
        cls.src = FIX / EXPECTED["transfers"][0]["file"]
        cls.raw = cls.src.read_bytes()

    def write(self, name: str, data: bytes) -> Path:
        p = TMP / name
        p.write_bytes(data)
        return p

    def refuses(self, path, message, xxh3=None, loader=read_archive):
        with self.assertRaises(ArchiveError) as cm:
            loader(path, xxh3=xxh3)
        self.assertEqual(str(cm.exception), f"{path}: {message}")
        self.assertEqual(cm.exception.path, str(path))

    def test_flipped_byte_anywhere_is_a_checksum_mismatch(self):
        n = len(self.raw)
        positions = sorted(
            set(list(range(8, 48)) + list(range(48, n, 97)) + list(range(n - 40, n)))
        )
        for i, pos in enumerate(positions):
            data = bytearray(self.raw)
            data[pos] ^= 0x01
            p = self.write("flipped.prt", bytes(data))
            # Both implementations, the numpy one on every fourth position (it is slower).
            for impl in (None, "numpy") if i % 4 == 0 else (None,):
                with self.subTest(position=pos, xxh3=impl):
                    self.refuses(p, "checksum mismatch (file corrupt)", impl)

    def test_flipped_magic_is_not_an_archive(self):
        for pos in range(8):
            data = bytearray(self.raw)
            data[pos] ^= 0x20
            p = self.write("magic.prt", bytes(data))
            self.refuses(p, "not a prtlab archive (it does not start with the PRTLAB magic)")

    def test_truncated_at_any_length(self):
        n = len(self.raw)
        self.refuses(self.write("empty.prt", b""), "empty file (not a prtlab archive)")
        for m in list(range(1, 24)):
            self.refuses(
                self.write("short.prt", self.raw[:m]),
                f"truncated: file has {m} bytes, the smallest archive has 80",
            )
        for m in list(range(24, 200, 7)) + list(range(200, n, 211)) + [n - 17, n - 16, n - 1]:
            with self.subTest(length=m):
                self.refuses(
                    self.write("trunc.prt", self.raw[:m]),
                    f"truncated: expected {n} bytes, file has {m}",
                )

    def test_trailing_data(self):
        n = len(self.raw)
        self.refuses(
            self.write("long.prt", self.raw + b"extra"),
            f"5 bytes of unexpected data after the end of the archive "
            f"(expected {n} bytes, file has {n + 5})",
        )

    def test_damaged_length_field_with_intact_trailer(self):
        data = bytearray(self.raw)
        data[16:24] = (len(self.raw) + 64).to_bytes(8, "little")
        self.refuses(self.write("len.prt", bytes(data)), "checksum mismatch (file corrupt)")

    def test_foreign_file(self):
        self.refuses(
            self.write("foreign.txt", b"hello, this is not an archive at all" * 4),
            "not a prtlab archive (it does not start with the PRTLAB magic)",
        )

    def test_missing_file_and_directory(self):
        self.refuses(TMP / "does-not-exist.prt", "cannot open: No such file or directory")
        self.refuses(TMP, "is a directory, not an archive")

    def test_unknown_element_type(self):
        data = build_archive("x", 1, {}, [("a", 11, 2, bytes(2))])
        self.refuses(
            self.write("tag.prt", data),
            "malformed archive (file corrupt): section 'a' has unknown element type 11",
        )
        data = build_archive("x", 1, {}, [("a", 0, 2, bytes(2))])
        self.refuses(
            self.write("tag0.prt", data),
            "malformed archive (file corrupt): section 'a' has unknown element type 0",
        )

    def test_inconsistent_records_with_a_valid_checksum(self):
        data = build_archive("x", 1, {}, [("a", 5, 3, bytes(8))])
        self.refuses(
            self.write("count.prt", data),
            "malformed archive (file corrupt): section 'a' holds 8 bytes, not 3 uint32 elements",
        )
        a = np.arange(3, dtype=np.uint32)
        data = build_archive("x", 1, {}, [("a", a), ("a", a)])
        self.refuses(
            self.write("twice.prt", data),
            "malformed archive (file corrupt): section 'a' appears twice",
        )

    def test_newer_format_version(self):
        data = build_archive("x", 1, {}, [], format_version=2)
        self.refuses(
            self.write("v2.prt", data),
            "format version 2 is newer than this reader supports (1); "
            "update prtlab or delete the file",
        )

    def test_kind_and_kind_version(self):
        comp = FIX / EXPECTED["compressed"][0]["file"]
        self.refuses(
            comp,
            "artifact kind is 'compressed-transfer', expected 'transfer-matrix'",
            loader=load_transfer,
        )
        self.refuses(
            self.src,
            "artifact kind is 'transfer-matrix', expected 'compressed-transfer'",
            loader=load_compressed,
        )
        a = read_archive(self.src)
        data = build_archive("transfer-matrix", 2, a.metadata, list(a.sections.items()))
        self.refuses(
            self.write("kv2.prt", data),
            "'transfer-matrix' version 2 is newer than this reader supports (1); "
            "update prtlab or delete the file",
            loader=load_transfer,
        )

    def test_invalid_csr_with_a_valid_checksum(self):
        a = read_archive(self.src)
        s = {k: np.array(v) for k, v in a.sections.items()}
        m, n = a.metadata["local_count"], a.metadata["pixel_count"]

        def refused_with(sections, what):
            data = build_archive("transfer-matrix", 1, a.metadata, list(sections.items()))
            self.refuses(
                self.write("csr.prt", data),
                f"invalid transfer matrix: {what}",
                loader=load_transfer,
            )

        bad = dict(s, counts=s["counts"].copy())
        bad["counts"][5] = 0
        refused_with(bad, "a count is outside 1..s^2 = 4")
        bad = dict(s, columns=s["columns"].copy())
        bad["columns"][3] = n
        refused_with(bad, f"a column index is >= N = {n}")
        # Swap two columns of one row: no longer strictly increasing.
        offsets = s["row_offsets"]
        row = int(np.argmax(np.diff(offsets) >= 2))
        bad = dict(s, columns=s["columns"].copy())
        i = int(offsets[row])
        bad["columns"][[i, i + 1]] = bad["columns"][[i + 1, i]]
        refused_with(bad, "columns are not strictly increasing within a row")
        # A column of one vertex's block used in two of its rows.
        v = next(
            v
            for v in range(a.metadata["vertices"])
            if np.count_nonzero(np.diff(offsets[v * m : v * m + m + 1])) >= 2
        )
        rows = [r for r in range(v * m, v * m + m) if offsets[r + 1] > offsets[r]]
        r0, r1 = rows[0], rows[1]
        c0 = int(s["columns"][offsets[r0]])
        row1 = s["columns"][offsets[r1] : offsets[r1 + 1]]
        if c0 in row1:
            self.fail("fixture rows already share a column")
        bad = dict(s, columns=s["columns"].copy())
        new_row = np.sort(np.concatenate([row1[1:], [c0]])).astype(row1.dtype)
        bad["columns"][offsets[r1] : offsets[r1 + 1]] = new_row
        refused_with(bad, "a column holds two entries in one vertex block")
        bad = dict(s, row_offsets=s["row_offsets"][:-1].copy())
        refused_with(
            bad,
            f"{offsets.size - 1} row offsets for {offsets.size - 1} rows "
            f"(expected {offsets.size})",
        )


class WithoutOptionalModules(unittest.TestCase):
    """numpy alone: scipy and xxhash made unimportable in a fresh interpreter."""

    def test_dict_form_and_numpy_checksum(self):
        e = EXPECTED["transfers"][0]
        code = (
            "import sys, json\n"
            "sys.modules['scipy'] = None\n"
            "sys.modules['xxhash'] = None\n"
            "import prtlab\n"
            f"t = prtlab.load_transfer({str(FIX / e['file'])!r})\n"
            "m = t.matrix\n"
            "print(json.dumps([prtlab.xxhash_available(), type(m).__name__, sorted(m),\n"
            "                  list(m['shape']), int(m['data'].size)]))\n"
        )
        r = subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            env=dict(os.environ),
            timeout=120,
        )
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(
            json.loads(r.stdout),
            [
                False,
                "dict",
                ["data", "indices", "indptr", "shape"],
                [e["rows"], e["pixel_count"]],
                e["nnz"],
            ],
        )


class StageCacheAndCli(unittest.TestCase):
    """Files the prtlab CLI wrote: a stage-cache T and `compress --save` of every backend."""

    @classmethod
    def setUpClass(cls):
        cls.cli = os.environ.get("PRTLAB_TEST_CLI")
        if not cls.cli:
            raise RuntimeError("PRTLAB_TEST_CLI (the prtlab-test executable) is not set")
        cls.cache = TMP / "cache"
        cls.env = dict(os.environ, PRTLAB_CACHE=str(cls.cache))

    def run_cli(self, *args):
        r = subprocess.run(
            [self.cli, "-q", "--no-opencl", *args, "--json"],
            env=self.env,
            capture_output=True,
            text=True,
            timeout=240,
        )
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout)

    def test_cached_transfer_and_saved_compressions(self):
        pre = self.run_cli("precompute", "tiny-sphere-plane")
        path = Path(pre["cache_file"])
        self.assertEqual(path.parent, self.cache / "transfer")
        t = load_transfer(path)
        self.assertEqual(t.shape, (pre["rows"], pre["columns"]))
        self.assertEqual(t.nnz, pre["nnz"])
        self.assertEqual(t.supersampling, pre["supersampling"])
        self.assertEqual(t.vertices, pre["vertices"])
        a = read_archive(path)
        self.assertEqual(sum(x.nbytes for x in a.sections.values()), pre["stored_bytes"])
        self.assertEqual(a.metadata["stage_cache"], {"stage": "transfer", "key": path.stem})

        backends = [b["name"] for b in self.run_cli("list")["backends"]]
        self.assertIn("uncompressed", backends)
        for b in backends:
            with self.subTest(backend=b):
                saved = TMP / f"saved_{b}.prt"
                rep = self.run_cli(
                    "compress",
                    "tiny-sphere-plane",
                    "--backend",
                    b,
                    "--lights",
                    "1",
                    "--repeat",
                    "1",
                    "--save",
                    str(saved),
                )
                c = load_compressed(saved)
                self.assertEqual(c.backend, b)
                self.assertEqual(c.storage_bytes, rep["storage_bytes"])
                self.assertAlmostEqual(
                    c.flops_per_relight / 1e6, rep["mflops_per_relight"], places=6
                )
                if b == "uncompressed":
                    np.testing.assert_array_equal(c.arrays["counts"], t.counts)


if __name__ == "__main__":
    unittest.main()
