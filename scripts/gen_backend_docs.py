#!/usr/bin/env python3
"""Regenerate the parameter block of every backend README from the registry.

    python3 scripts/gen_backend_docs.py [--cli PRTLAB] [--root DIR] [--check]

For each backend that `PRTLAB list --json` reports as built in, finds its README by folder name
(DIR/compressors/<name>/README.md or DIR/tests/backends/<name>/README.md) and replaces the text
between the lines `<!-- params:begin -->` and `<!-- params:end -->` with the output of
`PRTLAB list --markdown <name>`. The default PRTLAB is build/release/tests/prtlab-test, the CLI
with the test-only backends, so their READMEs are regenerated too; DIR defaults to the checkout
this script lives in. --check writes nothing and exits 1 when a block is stale.

Exits 1 when a backend has no README or its README lacks the markers (add them where the
parameter table belongs), 2 when the CLI cannot be run.
"""
import argparse
import json
import os
import subprocess
import sys

BEGIN = "<!-- params:begin -->\n"
END = "<!-- params:end -->"
FOLDERS = ("compressors", os.path.join("tests", "backends"))


def run_cli(cli, args):
    try:
        out = subprocess.run([cli, *args], check=True, capture_output=True, text=True)
    except (OSError, subprocess.CalledProcessError) as e:
        detail = getattr(e, "stderr", "") or str(e)
        print(f"gen_backend_docs: {cli} {' '.join(args)} failed: {detail.strip()}\n"
              "(build it first: cmake --build --preset release)", file=sys.stderr)
        sys.exit(2)
    return out.stdout


def find_readme(root, name):
    for folder in FOLDERS:
        path = os.path.join(root, folder, name, "README.md")
        if os.path.isfile(path):
            return path
    return None


def replace_block(text, block):
    """The text with its params block replaced, or None when the markers are missing."""
    start = text.find(BEGIN)
    end = text.find(END, start + len(BEGIN)) if start >= 0 else -1
    if start < 0 or end < 0:
        return None
    return text[: start + len(BEGIN)] + block + text[end:]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.dirname(here), help="checkout to rewrite")
    parser.add_argument("--cli", default=None,
                        help="prtlab executable (default: ROOT/build/release/tests/prtlab-test)")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 when stale")
    args = parser.parse_args()
    cli = args.cli or os.path.join(args.root, "build", "release", "tests", "prtlab-test")

    backends = json.loads(run_cli(cli, ["list", "--json"]))["backends"]
    problems, stale = [], []
    for backend in backends:
        if backend["origin"] != "built-in":
            continue  # a plugin's page lives with the plugin
        name = backend["name"]
        readme = find_readme(args.root, name)
        if readme is None:
            problems.append(f"{name}: no README.md under " + " or ".join(FOLDERS))
            continue
        with open(readme, encoding="utf-8") as f:
            text = f.read()
        new = replace_block(text, run_cli(cli, ["list", "--markdown", name]))
        if new is None:
            problems.append(f"{readme}: no '{BEGIN.strip()}' ... '{END}' block")
            continue
        if new == text:
            continue
        stale.append(readme)
        if not args.check:
            with open(readme, "w", encoding="utf-8") as f:
                f.write(new)
    for p in problems:
        print(f"gen_backend_docs: {p}", file=sys.stderr)
    for readme in stale:
        print(f"{'stale' if args.check else 'rewrote'}: {readme}")
    if problems or (args.check and stale):
        sys.exit(1)


if __name__ == "__main__":
    main()
