#!/usr/bin/env python3
"""Checks the user docs against the code and the binaries they describe.

* docs/TROUBLESHOOTING.md has a row for every robot ERROR code the vision
  app can return (the codes of the one error table, robot_errors.cpp) and
  for every WHY sentence (request_record.cpp, cell_commands.cpp) and its
  remedy clause, and no
  row for a code that no longer exists; docs/PROTOCOL.md's Errors table
  lists every code too. A new code or sentence without its line fails here.
* README.md: every relative link and every docs/*.md it names exists; every
  command line `build/bin/picksight-...` names a built binary, and every
  --option on it is one that binary's --help lists (a renamed flag fails).
* docs/ARCHITECTURE.md's namespace table against the code: the flat
  namespace `picksight` is opened only by the library its row names (and
  that library's tests), and every `picksight::x` product code opens has a
  row (a library moved back into `picksight`, or a new one left out, fails).

Usage: check_docs.py SOURCE_DIR BIN_DIR [with-bench|no-bench]
(no-bench: a build without the benchmarks; their lines are not run.)
"""
import pathlib
import re
import shlex
import subprocess
import sys

failures = []


def fail(message):
    failures.append(message)


def one_source(root, name):
    """The one file of that name under the source tree (it may move)."""
    found = [p for p in root.rglob(name) if "build" not in p.relative_to(root).parts[0]]
    if len(found) != 1:
        fail(f"expected one {name} in the source tree, found {len(found)}: {found}")
        return ""
    return found[0].read_text()


def table_rows(markdown, heading):
    """First cells of the table under `## heading` (up to the next ##)."""
    match = re.search(r"^## " + re.escape(heading) + r"\n(.*?)(?=^## |\Z)", markdown, re.M | re.S)
    if not match:
        fail(f"no section '## {heading}'")
        return []
    return [line.split("|")[1].strip() for line in match.group(1).splitlines()
            if line.startswith("|") and not line.startswith("|---")]


def check_error_codes(root):
    table = one_source(root, "robot_errors.cpp")
    body = re.search(r"kTable\[\] = \{(.*?)\n\};", table, re.S)
    if not body:
        fail("robot_errors.cpp: no kTable found")
        return
    codes = {int(c) for c in re.findall(r",\s*(\d+)\s*\}", body.group(1))}
    internal = re.search(r"kInternal = (\d+);", table)
    if internal:
        codes.add(int(internal.group(1)))
    # 22 is also the video server's answer to anything else (robotErrorCode).
    if len(codes) < 30:
        fail(f"robot_errors.cpp: only {len(codes)} codes read; has the table's form changed?")
    trouble = (root / "docs/TROUBLESHOOTING.md").read_text()
    rows = table_rows(trouble, "ERROR codes")
    listed = {int(r) for r in rows if r.isdigit()}
    for code in sorted(codes - listed):
        fail(f"docs/TROUBLESHOOTING.md: ERROR {code} has no row in 'ERROR codes'")
    for code in sorted(listed - codes):
        fail(f"docs/TROUBLESHOOTING.md: ERROR {code} is listed but robot_errors.cpp has no such code")
    protocol = (root / "docs/PROTOCOL.md").read_text()
    documented = {int(r) for r in table_rows(protocol, "Errors") if r.isdigit()}
    for code in sorted(codes - documented):
        fail(f"docs/PROTOCOL.md: ERROR {code} is not in the Errors table")


def check_why_sentences(root):
    record = one_source(root, "request_record.cpp")
    commands = one_source(root, "cell_commands.cpp")
    # rejectionText: each sentence is `region + " <words>..."`.
    starts = {s.rstrip() for s in re.findall(r'region \+ "( [^"]+)"', record)}
    # The whole replies: "OK 0 ..." literals and the two ends of WHY's line.
    whole = set(re.findall(r'"OK 0 ([^"]+)"', record + commands))
    for a, b in re.findall(r'why_ \+= [^;]*\? " ([^"]+)" : " ([^"]+)"', record):
        whole.update((a, b))
    if len(starts) < 10 or len(whole) < 4:
        fail(f"WHY sentences: read {len(starts)} region sentences and {len(whole)} replies;"
             " has the code's form changed?")
    trouble = (root / "docs/TROUBLESHOOTING.md").read_text()
    rows = table_rows(trouble, "WHY: why a region was left out")
    for start in sorted(starts):
        if not any(r.startswith("`region <r>" + start) for r in rows):
            fail(f"docs/TROUBLESHOOTING.md: no WHY row for 'region <r>{start} ...'")
    for reply in sorted(whole):
        if not any(r.startswith("`OK 0 " + reply.rstrip()) for r in rows):
            fail(f"docs/TROUBLESHOOTING.md: no WHY row for 'OK 0 {reply}'")
    # The remedy's clause after a sentence (remedyText): ", <key> <value> ...".
    for clause in set(re.findall(r'" ([a-z ]+ it)";', record)):
        if not any(clause in r for r in rows):
            fail(f"docs/TROUBLESHOOTING.md: no WHY row for the remedy '..., <key> <value> {clause}'")


def check_readme(root, bin_dir, with_bench):
    readme = (root / "README.md").read_text()
    for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", readme):
        if not (root / target).exists():
            fail(f"README.md links to {target}, which does not exist")
    for doc in set(re.findall(r"\bdocs/[A-Za-z_-]+\.md\b", readme)):
        if not (root / doc).exists():
            fail(f"README.md names {doc}, which does not exist")
    helps = {}
    for line in readme.splitlines():
        line = line.strip()
        if not line.startswith("build/bin/picksight-"):
            continue
        words = shlex.split(line, comments=True)
        binary = bin_dir / pathlib.Path(words[0]).name
        if not with_bench and binary.name.startswith("picksight-bench-"):
            continue
        if not binary.exists():
            fail(f"README.md runs {words[0]}, which the build does not make")
            continue
        options = [w.split("=")[0] for w in words[1:] if w.startswith("--")]
        if not options:
            continue
        if binary not in helps:
            run = subprocess.run([str(binary), "--help"], capture_output=True, text=True,
                                 timeout=30)
            helps[binary] = run.stdout + run.stderr
        for option in options:
            if not re.search(re.escape(option) + r"\b", helps[binary]):
                fail(f"README.md: '{line}': {binary.name} --help has no {option}")


def namespace_table(architecture):
    """{namespace: library cell} from the table after 'Namespaces:'."""
    match = re.search(r"^Namespaces:.*?\n\n((?:\|[^\n]*\n)+)", architecture, re.M | re.S)
    if not match:
        fail("docs/ARCHITECTURE.md: no namespace table after 'Namespaces:'")
        return {}
    table = {}
    for line in match.group(1).splitlines()[2:]:
        cells = [c.strip() for c in line.split("|")[1:-1]]
        prefix = None
        for name in re.findall(r"`([\w:]+)`", cells[0]):
            # `picksight::a`, `::b`: the second is picksight::b
            full = prefix + name if name.startswith("::") and prefix else name
            prefix = full.rsplit("::", 1)[0] if "::" in full else full
            table[full] = cells[1]
    return table


def check_namespaces(root):
    table = namespace_table((root / "docs" / "ARCHITECTURE.md").read_text())
    if "picksight" not in table:
        fail("docs/ARCHITECTURE.md: the namespace table has no row for `picksight`")
        return
    # The folder of the one library the flat namespace belongs to.
    flat_owner = re.findall(r"`([\w/]+)`", table["picksight"])[:1]
    sources = [p for p in root.rglob("*") if p.suffix in (".cpp", ".hpp", ".h")
               and "build" not in p.relative_to(root).parts[0]]
    for path in sources:
        parts = path.relative_to(root).parts
        text = path.read_text(errors="replace")
        if re.search(r"^namespace picksight \{", text, re.M):
            owned = parts[0] in flat_owner or (parts[0] == "tests" and parts[1] in flat_owner)
            if not owned:
                fail(f"{path.relative_to(root)}: opens the flat namespace `picksight`, "
                     f"which docs/ARCHITECTURE.md gives to {', '.join(flat_owner)} alone")
        if parts[0] == "tests":
            continue  # tests and their fixtures name namespaces of their own
        for name in re.findall(r"^namespace (picksight::\w+)", text, re.M):
            if name not in table:
                fail(f"{path.relative_to(root)}: namespace {name} has no row in "
                     "docs/ARCHITECTURE.md's namespace table")


def main():
    if len(sys.argv) not in (3, 4) or sys.argv[3:] not in ([], ["with-bench"], ["no-bench"]):
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(sys.argv[1]).resolve()
    bin_dir = pathlib.Path(sys.argv[2]).resolve()
    check_error_codes(root)
    check_why_sentences(root)
    check_readme(root, bin_dir, sys.argv[3:] != ["no-bench"])
    check_namespaces(root)
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    if not failures:
        print("docs agree with the code and the binaries")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
