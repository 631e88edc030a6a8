#!/usr/bin/env python3
"""Fails on a results file that does not say where it came from.

A number quoted from results/ is trusted only when the file holding it names the command that
wrote it and the clean commit it was written at. This script checks every report under results/:

  * every folder holding result files is covered by a report: a README.md in it or in a folder
    above it (below results/; results/README.md is the index and covers nothing), and every
    file at the top of results/ by a report of the same stem (table1.csv by table1.md);
  * every report (each README.md below results/, each *.md at its top, and each other *.md that
    no README.md in or above its folder covers) names a git commit that exists in
    this repository's history ("git <hash>", "git: <hash>", "commit <hash>", or "this folder's
    commit") and a command (a line or code span that runs `prtlab`, a build/ binary, a
    `bench/` binary, a `scripts/` file, `python3`, `ctest` or `cmake`);
  * no report says its tree was dirty ("(dirty)", "<hash>-dirty", "(working tree modified)"),
    and no prtlab results JSON records "git_dirty": true or lacks its git hash.

Files written before this check existed that break it are listed, with the reason and the
command that would regenerate them, in results/PROVENANCE-DEBT.md (a table whose first column
is a path or glob below the repository root). A problem in a listed file is reported as known
debt and does not fail the check; a listed entry that matches no file, or whose files no longer
have a problem, fails it, so the list only shrinks.

Usage: scripts/check_results_provenance.py [--root DIR] [--no-git] [--verbose]
Exit status 0 when every problem is known debt, 1 otherwise (one line per problem), 2 on bad
input (no results folder, an unreadable ledger).
"""
from __future__ import annotations

import argparse
import fnmatch
import json
import re
import subprocess
import sys
from pathlib import Path

HASH = re.compile(r"\b(?:git|commit|build of|built from|tree of|after)\b[\s:|`(]{1,6}([0-9a-f]{7,40})\b")
FOLDER_COMMIT = re.compile(r"this folder's commit")
COMMAND = re.compile(
    r"(\bprtlab\b\s+[a-z]|build/release/|\bbench/\w|scripts/[\w.-]+\.(?:sh|py)|\bpython3?\s+\S|"
    r"\bctest\b|\bcmake\b)")
DIRTY = re.compile(r"\(dirty\)|\b[0-9a-f]{7,40}-dirty\b|\(working tree modified\)|working tree dirty")
LEDGER = "PROVENANCE-DEBT.md"


class Problem:
    def __init__(self, path: str, message: str) -> None:
        self.path = path  # relative to the repository root, no line number
        self.message = message

    def __str__(self) -> str:
        return f"{self.path}{self.message}"


def commit_exists(repo: Path, sha: str, cache: dict[str, bool]) -> bool:
    if sha not in cache:
        r = subprocess.run(["git", "-C", str(repo), "cat-file", "-e", f"{sha}^{{commit}}"],
                           capture_output=True)
        cache[sha] = r.returncode == 0
    return cache[sha]


def reports_under(results: Path) -> list[Path]:
    return [p for p in sorted(results.rglob("*.md"))
            if p != results / "README.md" and p != results / LEDGER]


def covered(folder: Path, results: Path) -> bool:
    d = folder
    while d != results:
        if (d / "README.md").is_file():
            return True
        d = d.parent
    return False


def find_problems(results: Path, repo: Path, use_git: bool) -> list[Problem]:
    problems: list[Problem] = []
    known: dict[str, bool] = {}

    def rel(p: Path) -> str:
        return p.relative_to(repo).as_posix()

    for folder in sorted({p.parent for p in results.rglob("*") if p.is_file()}):
        files = [p for p in folder.iterdir() if p.is_file()]
        if folder == results:
            stems = {p.stem for p in files if p.suffix == ".md"}
            for f in files:
                if f.suffix != ".md" and f.stem not in stems:
                    problems.append(Problem(rel(f), f": no report ({f.stem}.md) says how it was made"))
        elif not covered(folder, results) and not any(p.suffix == ".md" for p in files):
            problems.append(Problem(rel(folder) + "/", ": no README.md in or above it says how its files were made"))

    for report in reports_under(results):
        text = report.read_text(errors="replace")
        hashes = list(dict.fromkeys(HASH.findall(text)))
        # A table beside a README (tables.md) is that README's data: the README names the
        # command and the commit. Any report is checked for a dirty tree.
        own = report.name == "README.md" or report.parent == results or not covered(report.parent, results)
        if not own:
            pass
        elif not hashes and not FOLDER_COMMIT.search(text):
            problems.append(Problem(rel(report), ": names no git commit (\"git <hash>\", \"commit <hash>\")"))
        elif hashes and use_git and not any(commit_exists(repo, h, known) for h in hashes):
            problems.append(Problem(rel(report), f": none of its commits ({', '.join(hashes)}) is in this repository's history"))
        if own and not COMMAND.search(text):
            problems.append(Problem(rel(report), ": names no command that wrote it"))
        for lineno, line in enumerate(text.splitlines(), 1):
            if DIRTY.search(line):
                problems.append(Problem(rel(report), f":{lineno}: written from a dirty tree: {line.strip()[:100]}"))

    for js in sorted(results.rglob("*.json")):
        try:
            data = json.loads(js.read_text(errors="replace"))
        except json.JSONDecodeError as e:
            problems.append(Problem(rel(js), f": not valid JSON ({e})"))
            continue
        prov = data.get("provenance") if isinstance(data, dict) else None
        if not isinstance(prov, dict):
            continue
        if not prov.get("git"):
            problems.append(Problem(rel(js), ": its provenance names no git hash"))
        if prov.get("git_dirty") is True or str(prov.get("git", "")).endswith("-dirty"):
            problems.append(Problem(rel(js), f": its provenance says the tree was dirty (git {prov.get('git')})"))
    return problems


def read_ledger(path: Path) -> list[str]:
    """The first column of every table row that names a path (a code span or bare)."""
    if not path.exists():
        return []
    entries = []
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.lstrip().startswith("|") or len(cells) < 2:
            continue
        first = cells[0].strip("`")
        if first and first.startswith("results/"):
            entries.append(first)
    return entries


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                    help="repository root (default: this script's repository)")
    ap.add_argument("--no-git", action="store_true", help="do not check that commits exist")
    ap.add_argument("--verbose", action="store_true", help="also print the known debt")
    args = ap.parse_args()
    repo = args.root.resolve()
    results = repo / "results"
    if not results.is_dir():
        print(f"{results}: no results folder", file=sys.stderr)
        return 2
    try:
        ledger = read_ledger(results / LEDGER)
    except OSError as e:
        print(f"{results / LEDGER}: {e}", file=sys.stderr)
        return 2
    use_git = not args.no_git
    if use_git:
        r = subprocess.run(["git", "-C", str(repo), "rev-parse", "--is-shallow-repository"],
                           capture_output=True, text=True)
        if r.returncode != 0 or r.stdout.strip() != "false":
            why = "not a git checkout" if r.returncode != 0 else "a shallow clone"
            print(f"{repo}: {why}: commits are not checked against the history", file=sys.stderr)
            use_git = False
    problems = find_problems(results, repo, use_git)

    def listed(path: str) -> str | None:
        for entry in ledger:
            if fnmatch.fnmatchcase(path, entry) or fnmatch.fnmatchcase(path.rstrip("/"), entry.rstrip("/")):
                return entry
        return None

    new = [p for p in problems if listed(p.path) is None]
    debt = [p for p in problems if listed(p.path) is not None]
    stale = []
    for entry in ledger:
        matches = [p for p in repo.glob(entry.rstrip("/"))]
        if not matches:
            stale.append(f"results/{LEDGER}: `{entry}` matches no file: remove it from the ledger")
        elif not any(listed(p.path) == entry for p in debt):
            stale.append(f"results/{LEDGER}: `{entry}` has no provenance problem any more: remove it from the ledger")
    for p in new:
        print(p)
    for s in stale:
        print(s)
    if args.verbose:
        for p in debt:
            print(f"known debt: {p}")
    print(f"results provenance: {len(reports_under(results))} reports checked, {len(new)} problems, "
          f"{len(stale)} stale ledger entries, {len(debt)} known (results/{LEDGER})", file=sys.stderr)
    return 1 if new or stale else 0


if __name__ == "__main__":
    sys.exit(main())
