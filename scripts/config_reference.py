#!/usr/bin/env python3
"""Writes docs/config-reference.md from the executables' --help-config (the typed schema), or checks it is current.

  scripts/config_reference.py [--bin-dir build]          regenerate the page
  scripts/config_reference.py --check [--bin-dir build]  exit 1 when the page differs from what the schema says
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGE = os.path.join(ROOT, "docs", "config-reference.md")
# (executable, subcommand, what its config is for)
CONFIGS = [
    ("infinisplat-train", None, "Training (`infinisplat-train --config`): the model, data, losses and optimizer"),
    ("infinisplat-eval", None, "Evaluation (`infinisplat-eval --config`): datasets, protocol, methods and scoring"),
    ("infinisplat-experiment", None, "Experiments (`infinisplat-experiment --config`): ablation rows and seeds"),
    ("infinisplat", "generate", "Synthetic data (`infinisplat generate`)"),
    ("infinisplat", "eval-depth", "Depth-prior evaluation (`infinisplat eval-depth`)"),
]
SECTION = re.compile(r"^\[(?P<key>.+?)\]\s+(?P<doc>.*)$")
OPTION = re.compile(r"^  (?P<key>\S+)\s+\((?P<spec>.*)\)$")


def cell(text):
    return text.replace("|", "\\|").strip()


def to_markdown(text):
    """--help-config's plain text as Markdown tables, one per config section."""
    out, rows = [], []

    def flush():
        if rows:
            out.append("| key | type and default | meaning |")
            out.append("|---|---|---|")
            out.extend(f"| `{k}` | {cell(s)} | {cell(' '.join(d))} |" for k, s, d in rows)
            out.append("")
            rows.clear()

    for line in text.splitlines():
        if not line.strip():
            continue
        m = SECTION.match(line)
        if m:
            flush()
            out.append(f"#### `{m['key']}`: {m['doc'].strip()}")
            out.append("")
            continue
        m = OPTION.match(line)
        if m:
            rows.append((m["key"], m["spec"], []))
        elif line.startswith("      ") and rows:
            rows[-1][2].append(line.strip())
        else:
            raise SystemExit(f"config_reference.py: cannot read this --help-config line: {line!r}")
    flush()
    return out


def render(bin_dir):
    lines = [
        "# Configuration reference",
        "",
        "Every key of every config file: its type, default, allowed values and meaning. Generated from the typed",
        "schema (`--help-config`) by `scripts/config_reference.py`; a test fails when this page is stale. Set any key",
        "with `--set a.b=value`; a config may start from another with `\"base\": \"other.json\"`.",
        "",
    ]
    for exe, sub, title in CONFIGS:
        path = os.path.join(bin_dir, exe)
        cmd = [path] + ([sub] if sub else []) + ["--help-config"]
        try:
            text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        except (OSError, subprocess.CalledProcessError) as e:
            raise SystemExit(f"config_reference.py: {' '.join(cmd)} failed ({e}); build first (scripts/build.sh)")
        lines += [f"## {title}", ""] + to_markdown(text)
    return "\n".join(lines).rstrip() + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail when the page is stale instead of writing it")
    ap.add_argument("--bin-dir", default=os.path.join(ROOT, "build"), help="folder with the built executables")
    args = ap.parse_args()
    page = render(args.bin_dir)
    if args.check:
        current = open(PAGE).read() if os.path.exists(PAGE) else ""
        if current != page:
            print(f"config_reference.py: {PAGE} is stale; run scripts/config_reference.py", file=sys.stderr)
            return 1
        print(f"config_reference.py: {PAGE} is current")
        return 0
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(PAGE), prefix=".config-reference.", suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        f.write(page)
    os.replace(tmp, PAGE)
    print(f"config_reference.py: wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
