#!/usr/bin/env python3
"""Checks a hom JSON report against the schema of DESIGN.md ("Machine-readable
reports"): one object {"tool", "version", "cases"}; every case names itself
(name, family, p, elements, nodes, stage) and, where it carries quality
statistics, has all of min_q, max_q, mean_q, std_q, inverted with
0 <= min_q <= mean_q <= max_q <= 1; `thesis` and `peer` entries, where
present, are objects.

usage: check_report_schema.py REPORT.json [--tool NAME] [--stage S ...]
  --tool   the report must come from this tool
  --stage  some case must have this stage (repeatable)
Exit 0 when the report conforms, 1 with one line per problem otherwise.
"""
import json
import sys

IDENTITY = {"name": str, "family": str, "p": int, "elements": int, "nodes": int, "stage": str}
QUALITY = ("min_q", "max_q", "mean_q", "std_q", "inverted")
NUMERIC = ("min_scaled_jacobian", "time_s", "iterations", "peak_rss_mb")


def problems_of_case(i, case):
    where = f"case {i} ({case.get('name', '?')}/{case.get('stage', '?')})"
    for key, kind in IDENTITY.items():
        if key not in case:
            yield f"{where}: missing '{key}'"
        elif not isinstance(case[key], kind) or isinstance(case[key], bool):
            yield f"{where}: '{key}' is {type(case[key]).__name__}, expected {kind.__name__}"
    if isinstance(case.get("p"), int) and case["p"] < 1:
        yield f"{where}: p = {case['p']} < 1"
    present = [k for k in QUALITY if k in case]
    if present and len(present) != len(QUALITY):
        yield f"{where}: quality statistics incomplete, missing {sorted(set(QUALITY) - set(present))}"
    if len(present) == len(QUALITY):
        lo, mean, hi = case["min_q"], case["mean_q"], case["max_q"]
        if not (0.0 <= lo <= mean + 1e-12 and mean <= hi + 1e-12 and hi <= 1.0 + 1e-12):
            yield f"{where}: quality statistics out of order: min {lo} mean {mean} max {hi}"
        if not isinstance(case["inverted"], int) or case["inverted"] < 0:
            yield f"{where}: 'inverted' must be a non-negative integer"
    for key in NUMERIC:
        if key in case and not isinstance(case[key], (int, float)):
            yield f"{where}: '{key}' must be a number"
    for key in ("thesis", "peer"):
        if key in case and case[key] is not None and not isinstance(case[key], dict):
            yield f"{where}: '{key}' must be an object"


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    path, args = argv[1], argv[2:]
    tool, stages = None, []
    while args:
        flag, value, args = args[0], args[1], args[2:]
        if flag == "--tool":
            tool = value
        elif flag == "--stage":
            stages.append(value)
        else:
            print(f"unknown option {flag}", file=sys.stderr)
            return 2
    try:
        with open(path) as f:
            report = json.load(f)
    except (OSError, ValueError) as e:
        print(f"{path}: {e}")
        return 1
    problems = []
    for key in ("tool", "version", "cases"):
        if key not in report:
            problems.append(f"{path}: missing top-level '{key}'")
    cases = report.get("cases", [])
    if not isinstance(cases, list) or not cases:
        problems.append(f"{path}: 'cases' must be a non-empty list")
        cases = []
    if tool is not None and report.get("tool") != tool:
        problems.append(f"{path}: tool is {report.get('tool')!r}, expected {tool!r}")
    for i, case in enumerate(cases):
        problems.extend(f"{path}: {p}" for p in problems_of_case(i, case))
    for stage in stages:
        if not any(c.get("stage") == stage for c in cases):
            problems.append(f"{path}: no case with stage {stage!r}")
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
