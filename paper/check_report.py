#!/usr/bin/python3
"""Checks a report written by paper/make (the meson test paper_quick runs it on a quick report):

    check_report.py REPORT.md

- the header names the command, the commit (40 hex digits), the date, the machine and the mode;
- every thesis table of TABLES (3.2 ... D.4, appendix C) has its section, in order;
- each section either has a table with thesis and hom columns holding numbers in at least one
  row, or says "Not reproduced yet" with a reason (never a hom column without numbers);
- every linked figure exists beside the report.
Exit 0 when all hold; otherwise every failure is printed and the exit status is 1.
"""

import os
import re
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_report import TABLES, heading  # noqa: E402  (the same list the report is built from)

NUMBER = re.compile(r"^-?\d+(\.\d+)?(e-?\d+)?$")


def sections(text):
    """{heading: body} of the '### ' sections."""
    parts = re.split(r"^### (.*)$", text, flags=re.M)
    return {parts[i].strip(): parts[i + 1] for i in range(1, len(parts) - 1, 2)}


def table_rows(body):
    rows = [[c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))] for line in body.splitlines()
            if line.startswith("|")]
    return (rows[0], rows[2:]) if len(rows) >= 2 else (None, [])


def check(path):
    failures = []
    text = open(path).read()
    head = text.split("## Runs")[0]
    for key, pattern in (("command", r"^- command: `paper/make[^`]*`"), ("commit", r"^- commit: [0-9a-f]{40}"),
                         ("date", r"^- date: \d{4}-\d\d-\d\d"), ("machine", r"^- machine: .*\d+ cores"),
                         ("mode", r"^- mode: (quick|full)")):
        if not re.search(pattern, head, re.M):
            failures.append("header: no %s line matching %r" % (key, pattern))
    secs = sections(text)
    order = []
    for tid, title, _ in TABLES:
        name = heading(tid, title)
        body = secs.get(name)
        if body is None:
            failures.append("no section '%s'" % name)
            continue
        order.append(list(secs).index(name))
        if "**Not reproduced yet:**" in body:
            if not re.search(r"\*\*Not reproduced yet:\*\* \S", body):
                failures.append("%s: not reproduced, without a reason" % name)
            continue
        header, rows = table_rows(body)
        if not header:
            failures.append("%s: no table" % name)
            continue
        thesis_cols = [i for i, h in enumerate(header) if "thesis" in h.lower()]
        hom_cols = [i for i, h in enumerate(header) if "hom" in h.lower()]
        if tid == "C":  # the thesis's numbers are in the text above hom's table
            thesis_ok = "Thesis (text of appendix C" in body
            hom_ok = any(NUMBER.match(r[i]) for r in rows for i in range(2, len(r)))
        else:
            thesis_ok = any(NUMBER.match(r[i]) for r in rows for i in thesis_cols if i < len(r))
            hom_ok = any(NUMBER.match(r[i]) for r in rows for i in hom_cols if i < len(r))
        if not thesis_ok:
            failures.append("%s: no thesis column with numbers" % name)
        if not hom_ok:
            failures.append("%s: no hom column with numbers" % name)
    if order != sorted(order):
        failures.append("table sections out of the thesis's order")
    base = os.path.dirname(os.path.abspath(path))
    for link in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
        if not os.path.exists(os.path.join(base, link)):
            failures.append("figure link %s: no such file" % link)
    return failures


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    failures = check(sys.argv[1])
    for f in failures:
        print("FAIL: " + f)
    if not failures:
        print("report %s: header, %d table sections and figure links conform" % (sys.argv[1], len(TABLES)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
