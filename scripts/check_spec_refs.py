#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks that every section reference in the tree names its document and an existing heading.

A reference is "section N", "sections N and M", "section N.M" or "§N". It must follow the name
of a Markdown document of the tree ("spec/format.md section 9.2", "`docs/design.md`,
section 4"), and that document must have a heading numbered N ("## 9. ..." or "### 9.2 ...").
Inside spec/*.md and docs/*.md a reference without a document name means the document itself.
Anywhere else a reference without a document is an error: after the specification
was renumbered, "spec section 8" could mean either numbering.

usage: scripts/check_spec_refs.py [FILE...]   (default: every tracked text file; exit 1 on errors)
       scripts/check_spec_refs.py --self-test   (known good and bad references are told apart)
"""
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TEXT = re.compile(r"(\.(c|cc|cpp|h|hpp|py|js|mjs|sh|md|txt|cmake|in|html|yml|yaml)|CMakeLists\.txt)$")
NUM = r"\d+(?:\.\d+)*"
# "section 9.2", "sections 9.1 to 9.3", "§4", "section 6, 7)"; a list continues only with numbers
# that end the phrase, so "(section 5, 21 models per slot)" is one reference to section 5.
REF = re.compile(
    r"(?:\b[Ss]ections?[ \t]+|§[ \t]*)(" + NUM + r")((?:[ \t]*(?:,|and|or|to|-)[ \t]*" + NUM +
    r"(?=[ \t]*(?:[),;:]|and\b|or\b|to\b|$)))*)")
DOC = re.compile(r"((?:spec|docs)/[\w.-]+\.md)[`'\"]?(?:,|[ \t]*\(|[ \t])*$")
# A line break inside a comment or docstring joins the words around it.
JOIN = re.compile(r"[ \t]*\n[ \t]*(?://+|#+(?![#\w])|\*(?!/)|<!--)?[ \t]*")


def headings(doc, cache={}):
    if doc not in cache:
        path = os.path.join(ROOT, doc)
        numbers = set()
        if os.path.isfile(path):
            with open(path, encoding="utf-8") as f:
                for line in f:
                    m = re.match(r"#{1,6}[ \t]+(" + NUM + r")\.?(?:[ \t]|$)", line)
                    if m:
                        numbers.add(m.group(1))
        cache[doc] = numbers if os.path.isfile(path) else None
    return cache[doc]


def check_file(rel):
    with open(os.path.join(ROOT, rel), encoding="utf-8", errors="replace") as f:
        text = f.read()
    # The joined text, with the line number of each of its characters.
    joined, line_of = [], []
    pos, line = 0, 1
    for m in JOIN.finditer(text):
        part = text[pos:m.start()]
        joined.append(part)
        line_of.extend([line] * len(part))
        joined.append(" ")
        line_of.append(line)
        line += 1
        pos = m.end()
    part = text[pos:]
    joined.append(part)
    line_of.extend([line] * len(part))
    joined = "".join(joined)
    self_doc = rel if re.match(r"(spec|docs)/[^/]+\.md$", rel) else None
    errors = []
    for m in REF.finditer(joined):
        line = line_of[m.start()] if m.start() < len(line_of) else 0
        numbers = [m.group(1)] + re.findall(NUM, m.group(2))
        before = DOC.search(joined[max(0, m.start() - 80):m.start()])
        doc = before.group(1) if before else self_doc
        if doc is None:
            errors.append(f"{rel}:{line}: '{m.group(0).strip()}' names no document "
                          f"(write e.g. 'spec/format.md section {numbers[0]}')")
            continue
        found = headings(doc)
        if found is None:
            errors.append(f"{rel}:{line}: '{doc}' does not exist")
            continue
        for n in numbers:
            if n not in found:
                errors.append(f"{rel}:{line}: {doc} has no section {n}")
    return errors


def self_test():
    good = ["// spec/format.md section 9.2", "// (spec/format.md, section 11.3, \"mixed\")",
            "// `spec/algorithm.md` (section 6 there)", "// spec/format.md sections 3, 4, 8 and 11",
            "// the counts of spec/format.md\n// section 12.", "# docs/design.md section 4",
            "// (spec/format.md section 9.6, 21 models per slot)"]
    bad = ["// spec section 9.2", "// (section 4)", "// spec/format.md section 16",
           "// spec/format.md section 9.17", "// spec/format.md sections 9.1 and 99",
           "// docs/none.md section 1", "// Section 2 of the spec", "// see §4"]
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for lines, want in ((good, 0), (bad, 1)):
            for text in lines:
                path = os.path.join(tmp, "case.cpp")
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text + "\n")
                got = len(check_file(path))
                if got != want:
                    print(f"self-test: {text!r}: {got} errors, expected {want}")
                    failed = 1
    print(f"check_spec_refs: self-test {'failed' if failed else 'passed'}", file=sys.stderr)
    return failed


def tracked_files():
    try:
        listed = subprocess.run(["git", "-C", ROOT, "ls-files"], capture_output=True, text=True,
                                check=True).stdout.split("\n")
    except (OSError, subprocess.CalledProcessError):  # not a git checkout: every file but builds
        listed = []
        for top, dirs, names in os.walk(ROOT):
            dirs[:] = [d for d in dirs if not d.startswith((".", "build", "corpus", "node_modules"))]
            listed += [os.path.relpath(os.path.join(top, n), ROOT) for n in names]
    # This script's own examples are not references.
    return [f for f in listed if f and TEXT.search(f) and f != "scripts/check_spec_refs.py"
            and os.path.isfile(os.path.join(ROOT, f))]


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    files = sys.argv[1:] or tracked_files()
    errors = []
    for rel in files:
        errors += check_file(rel)
    for e in errors:
        print(e)
    print(f"check_spec_refs: {len(files)} files, {len(errors)} bad section references",
          file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
