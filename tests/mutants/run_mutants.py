#!/usr/bin/env python3
"""Mutation runner: applies each mutant of mutants.tsv alone to a scratch
worktree of HEAD, rebuilds only the targets it names, runs the tests it names
and reports whether they killed it (failed) or it survived (all passed).

A tool, not a test: CTest does not know it and CI does not run it (a full run
rebuilds the touched library once per mutant). Debian tools only: git, cmake,
ccache, the compilers; no network.

    tests/mutants/run_mutants.py --check           # every mutant's text still in the code
    tests/mutants/run_mutants.py                   # all of them
    tests/mutants/run_mutants.py --file robot_camera --id plc-*
    tests/mutants/run_mutants.py --markdown        # the table for tests/README.md

The list's format is described atop mutants.tsv. The scratch worktree (git worktree
add of HEAD, under --work, default $TMPDIR/picksight-mutants) and its build
directory (build/ in it) are kept between runs: the next run moves the
worktree to HEAD in place and rebuilds only what changed. ccache's base_dir
is set to the worktree, so the first build takes the libraries from the
cache a developer's build filled. `git worktree remove` it when done for
good.
"""

import argparse
import fnmatch
import html
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
COLUMNS = ["id", "file", "what", "targets", "tests", "from", "to"]


@dataclass
class Mutant:
    line: int
    id: str
    file: str
    what: str
    targets: list
    tests: list
    old: str
    new: str
    result: str = ""
    killed_by: str = ""
    seconds: float = 0.0
    detail: list = field(default_factory=list)


def unescape(text):
    """\\n, \\t and \\\\ in the from and to columns (a mutant may span lines)."""
    out, i = [], 0
    while i < len(text):
        if text[i] == "\\" and i + 1 < len(text) and text[i + 1] in "nt\\":
            out.append({"n": "\n", "t": "\t", "\\": "\\"}[text[i + 1]])
            i += 2
        else:
            out.append(text[i])
            i += 1
    return "".join(out)


def read_list(path):
    mutants, errors, seen = [], [], set()
    for number, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if not raw.strip() or raw.startswith("#"):
            continue
        cells = raw.split("\t")
        if len(cells) != len(COLUMNS):
            errors.append(f"{path.name}:{number}: {len(cells)} columns, expected {len(COLUMNS)}")
            continue
        row = dict(zip(COLUMNS, cells))
        if row["id"] in seen:
            errors.append(f"{path.name}:{number}: id {row['id']} twice")
        seen.add(row["id"])
        tests = [t.strip() for t in row["tests"].split(" | ") if t.strip()]
        targets = [t.strip() for t in row["targets"].split(",") if t.strip()]
        if not tests or not targets:
            errors.append(f"{path.name}:{number}: {row['id']} names no test or no target")
        old, new = unescape(row["from"]), unescape(row["to"])
        if old == new:
            errors.append(f"{path.name}:{number}: {row['id']} changes nothing")
        mutants.append(Mutant(number, row["id"], row["file"], row["what"], targets, tests, old, new))
    return mutants, errors


def check_texts(mutants, repo, commit):
    """Every mutant's text must stand exactly once in its file at `commit`:
    the list follows the code."""
    errors, texts = [], {}
    for m in mutants:
        if m.file not in texts:
            p = subprocess.run(["git", "-C", str(repo), "show", f"{commit}:{m.file}"],
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
            texts[m.file] = p.stdout if p.returncode == 0 else None
        text = texts[m.file]
        if text is None:
            errors.append(f"{m.id}: no file {m.file}")
            continue
        count = text.count(m.old)
        if count != 1:
            errors.append(f"{m.id}: the text is found {count} times in {m.file} (must be once): {m.old!r}")
    return errors


def run(cmd, cwd=None, log=None, timeout=None):
    """Runs cmd; returns (exit code, output). A timeout counts as a failure (code -9)."""
    try:
        p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           text=True, errors="replace", timeout=timeout)
        code, out = p.returncode, p.stdout
    except subprocess.TimeoutExpired as e:
        code = -9
        out = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        out += f"\n(timed out after {timeout} s)"
    if log:
        with open(log, "a", encoding="utf-8") as f:
            f.write(f"$ {' '.join(shlex.quote(c) for c in cmd)}\n{out}\n(exit {code})\n")
    return code, out


def test_command(entry, build):
    """`ctest:REGEX` runs CTest's entries matching REGEX; `binary[:spec]` runs
    build/tests/binary with that Catch test spec (all its cases without one),
    reporting in XML so that the failing cases can be named."""
    if entry.startswith("ctest:"):
        return ["ctest", "--test-dir", str(build), "--no-tests=error", "--output-on-failure",
                "-R", entry[len("ctest:"):]]
    binary, _, spec = entry.partition(":")
    cmd = [str(build / "tests" / binary), "-r", "xml"]
    if spec:
        cmd.append(spec)
    return cmd


def failed_cases(entry, output):
    """The test cases an entry's output says failed (or crashed in), best effort."""
    if entry.startswith("ctest:"):
        return re.findall(r"^\s*\d+ - (.+?) \(", output, re.M)
    binary = entry.partition(":")[0]
    names = []
    # Catch's XML: each <TestCase name="..."> closes with an OverallResult;
    # a case without one is where the binary died.
    for match in re.finditer(r'<TestCase name="([^"]*)"(.*?)(?=<TestCase name=|\Z)', output, re.S):
        body = match.group(2)
        if 'OverallResult success="false"' in body or "OverallResult" not in body:
            names.append(html.unescape(match.group(1)))
    return [f"{binary}: {n}" for n in names]


def run_tests(entries, build, log, timeout, stop_at_first=True):
    """Returns the failing entries, each with the cases that failed (stops at
    the first failing entry when asked)."""
    failed = []
    for entry in entries:
        code, out = run(test_command(entry, build), cwd=build, log=log, timeout=timeout)
        if code != 0:
            failed.append((entry, failed_cases(entry, out) or [entry]))
            if stop_at_first:
                break
    return failed


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--list", type=Path, default=HERE / "mutants.tsv", help="the mutant list")
    ap.add_argument("--id", action="append", default=[], help="only these ids (glob; repeatable)")
    ap.add_argument("--file", action="append", default=[], help="only mutants of files containing this (repeatable)")
    ap.add_argument("--check", action="store_true", help="only check the list against the code (no build)")
    ap.add_argument("--work", type=Path, default=Path(tempfile.gettempdir()) / "picksight-mutants",
                    help="scratch directory: worktree, build dir (kept between runs) and logs")
    ap.add_argument("--jobs", type=int, default=2, help="build parallelism (default 2)")
    ap.add_argument("--timeout", type=int, default=900, help="seconds per test command (default 900)")
    ap.add_argument("--markdown", action="store_true", help="print the result table as Markdown")
    ap.add_argument("--clean", action="store_true", help="a fresh scratch worktree (the build dir stays)")
    args = ap.parse_args()

    repo = Path(run(["git", "-C", str(HERE), "rev-parse", "--show-toplevel"])[1].strip())
    mutants, errors = read_list(args.list)
    if args.id:
        mutants = [m for m in mutants if any(fnmatch.fnmatch(m.id, p) for p in args.id)]
    if args.file:
        mutants = [m for m in mutants if any(f in m.file for f in args.file)]
    # The list is checked against HEAD, the code the scratch worktree holds.
    head = run(["git", "-C", str(repo), "rev-parse", "HEAD"])[1].strip()
    errors += check_texts(mutants, repo, head)
    if errors:
        print("the mutant list does not follow the code:", file=sys.stderr)
        for e in errors:
            print("  " + e, file=sys.stderr)
        sys.exit(2)
    if not mutants:
        sys.exit("no mutant selected")
    print(f"{len(mutants)} mutants, every text found once in HEAD {head[:10]}")
    if args.check:
        return
    work = args.work.resolve()
    # The build directory inside the worktree, as a developer's (build/):
    # with ccache's base_dir set to the worktree its compilations read as
    # a developer tree's do, so the libraries come from the cache.
    src = work / "src"
    build = src / "build"
    os.environ["CCACHE_BASEDIR"] = str(src)
    work.mkdir(parents=True, exist_ok=True)
    # The worktree is kept between runs and moved to HEAD in place: files
    # that did not change keep their times, so the build dir stays current.
    if (src / ".git").exists() and not args.clean:
        code, out = run(["git", "-C", str(src), "checkout", "--force", "--detach", head])
    else:
        if src.exists():
            run(["git", "-C", str(repo), "worktree", "remove", "--force", str(src)])
        run(["git", "-C", str(repo), "worktree", "prune"])
        code, out = run(["git", "-C", str(repo), "worktree", "add", "--force", "--detach", str(src), head])
    if code != 0:
        sys.exit(f"cannot put HEAD in the scratch worktree {src}:\n{out}")
    try:
        log = work / "run.log"
        log.write_text("")
        cmake = ["cmake", "-S", str(src), "-B", str(build), "-DCMAKE_BUILD_TYPE=RelWithDebInfo",
                 "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_C_COMPILER_LAUNCHER=ccache"]
        if run(cmake, log=log)[0] != 0:
            sys.exit(f"cmake failed: see {log}")
        # The unmutated code must build and pass every test named, else a
        # "killed" would mean nothing.
        targets = sorted({t for m in mutants for t in m.targets})
        print(f"baseline: building {len(targets)} targets and running the named tests", flush=True)
        if run(["cmake", "--build", str(build), f"-j{args.jobs}", "--target", *targets], log=log)[0] != 0:
            sys.exit(f"the unmutated code does not build: see {log}")
        entries = list(dict.fromkeys(e for m in mutants for e in m.tests))
        failing = run_tests(entries, build, log, args.timeout, stop_at_first=False)
        if failing:
            sys.exit("the unmutated code fails: " + "; ".join(c for _, cases in failing for c in cases)
                     + f" (see {log})")

        for i, m in enumerate(mutants, 1):
            start = time.monotonic()
            path = src / m.file
            original = path.read_text(encoding="utf-8")
            try:
                path.write_text(original.replace(m.old, m.new, 1), encoding="utf-8")
                with open(log, "a", encoding="utf-8") as f:
                    f.write(f"\n==== {m.id}: {m.file}: {m.what}\n")
                code, _ = run(["cmake", "--build", str(build), f"-j{args.jobs}", "--target", *m.targets], log=log)
                if code != 0:
                    m.result = "no build"
                else:
                    failed = run_tests(m.tests, build, log, args.timeout)
                    m.result = "killed" if failed else "SURVIVED"
                    if failed:
                        cases = failed[0][1]
                        m.killed_by = cases[0] + (f" (and {len(cases) - 1} more)" if len(cases) > 1 else "")
            finally:
                path.write_text(original, encoding="utf-8")
            m.seconds = time.monotonic() - start
            print(f"[{i}/{len(mutants)}] {m.id}: {m.result} {m.killed_by} ({m.seconds:.0f} s)", flush=True)

        print()
        if args.markdown:
            print("| id | file | mutant | result | killed by |")
            print("|---|---|---|---|---|")
            for m in mutants:
                print(f"| {m.id} | {m.file} | {m.what} | {m.result} | {m.killed_by.replace('|', '/')} |")
        else:
            width = max(len(m.id) for m in mutants)
            for m in mutants:
                print(f"{m.id:<{width}}  {m.result:<8}  {m.file}: {m.what}  {m.killed_by}")
        survived = [m for m in mutants if m.result != "killed"]
        print(f"\n{len(mutants) - len(survived)} of {len(mutants)} killed"
              + (f"; not killed: {', '.join(m.id for m in survived)}" if survived else "")
              + f" (log: {log})")
        sys.exit(1 if survived else 0)
    finally:
        # A mutant interrupted half way is undone here too.
        run(["git", "-C", str(src), "checkout", "--force", "--detach", head])


if __name__ == "__main__":
    main()
