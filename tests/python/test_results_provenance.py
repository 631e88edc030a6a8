"""scripts/check_results_provenance.py on small results trees it must accept or refuse."""
import json
import os
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "check_results_provenance.py"


def git(repo: Path, *args: str) -> str:
    env = dict(os.environ, GIT_AUTHOR_NAME="t", GIT_AUTHOR_EMAIL="t@t", GIT_COMMITTER_NAME="t",
               GIT_COMMITTER_EMAIL="t@t")
    return subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True,
                          text=True, env=env).stdout.strip()


class ResultsProvenance(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory()
        self.repo = Path(self._tmp.name)
        git(self.repo, "init", "-q")
        (self.repo / "seed").write_text("x")
        git(self.repo, "add", "seed")
        git(self.repo, "commit", "-q", "-m", "seed")
        self.sha = git(self.repo, "rev-parse", "--short=12", "HEAD")
        (self.repo / "results").mkdir()
        (self.repo / "results" / "README.md").write_text("# index\n")

    def tearDown(self):
        self._tmp.cleanup()

    def write(self, rel: str, text: str) -> None:
        p = self.repo / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)

    def check(self):
        r = subprocess.run([sys.executable, str(SCRIPT), "--root", str(self.repo)],
                           capture_output=True, text=True)
        return r.returncode, r.stdout

    def good_report(self, extra: str = "") -> str:
        return (f"# run\n\n| command | `prtlab experiment run x` |\n"
                f"| provenance | prtlab 0.1.0 git {self.sha}, Release |\n{extra}")

    def test_a_report_with_command_and_clean_commit_passes(self):
        self.write("results/x/README.md", self.good_report())
        self.write("results/x/points.csv", "a,b\n1,2\n")
        self.write("results/x/result.json", json.dumps({"provenance": {"git": self.sha, "git_dirty": False}}))
        rc, out = self.check()
        self.assertEqual(rc, 0, out)

    def test_a_folder_without_a_report_fails(self):
        self.write("results/x/points.csv", "a,b\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("results/x/: no README.md", out)

    def test_a_report_without_a_commit_fails(self):
        self.write("results/x/README.md", "# run\n\n`prtlab experiment run x`\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("names no git commit", out)

    def test_a_commit_not_in_the_history_fails(self):
        self.write("results/x/README.md", "# run\n`prtlab compress bunny`, git 0123456789ab\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("is in this repository's history", out)

    def test_a_report_without_a_command_fails(self):
        self.write("results/x/README.md", f"# run\n\ngit {self.sha}\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("names no command", out)

    def test_a_dirty_tree_fails_in_the_report_and_in_json(self):
        self.write("results/x/README.md", self.good_report().replace(self.sha, self.sha + " (dirty)"))
        self.write("results/y/README.md", self.good_report())
        self.write("results/y/result.json", json.dumps({"provenance": {"git": self.sha, "git_dirty": True}}))
        self.write("results/y/fit.json", json.dumps({"provenance": {"git": self.sha + "-dirty"}}))
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("results/x/README.md:4: written from a dirty tree", out)
        self.assertIn("results/y/result.json: its provenance says the tree was dirty", out)
        self.assertIn("results/y/fit.json: its provenance says the tree was dirty", out)

    def test_a_table_beside_a_readme_is_covered_by_it_but_not_when_dirty(self):
        self.write("results/x/README.md", self.good_report())
        self.write("results/x/tables.md", "| a | b |\n|---|---|\n| 1 | 2 |\n")
        self.assertEqual(self.check()[0], 0)
        self.write("results/y/tables.md", "| a | b |\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("results/y/tables.md: names no git commit", out)
        self.write("results/y/tables.md", self.good_report())
        self.write("results/x/tables.md", f"git {self.sha} (dirty)\n")
        rc, out = self.check()
        self.assertIn("results/x/tables.md:1: written from a dirty tree", out)

    def test_a_top_level_file_needs_a_report_of_its_stem(self):
        self.write("results/table9.csv", "a\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("results/table9.csv: no report", out)
        self.write("results/table9.md", self.good_report())
        self.assertEqual(self.check()[0], 0)

    def test_the_ledger_excuses_listed_files_only_while_they_are_broken(self):
        self.write("results/x/README.md", "# old\n`prtlab fps bunny`\n")
        self.write("results/PROVENANCE-DEBT.md",
                   "| file | problem | regenerate with |\n|---|---|---|\n"
                   "| `results/x/*` | no commit | `prtlab fps bunny` |\n")
        rc, out = self.check()
        self.assertEqual(rc, 0, out)
        # Regenerated: the row is stale and must go.
        self.write("results/x/README.md", self.good_report())
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("has no provenance problem any more", out)

    def test_a_ledger_row_matching_nothing_fails(self):
        self.write("results/PROVENANCE-DEBT.md",
                   "| file | problem | regenerate with |\n|---|---|---|\n"
                   "| `results/gone/README.md` | no commit | `prtlab x` |\n")
        rc, out = self.check()
        self.assertEqual(rc, 1)
        self.assertIn("matches no file", out)


if __name__ == "__main__":
    unittest.main()
