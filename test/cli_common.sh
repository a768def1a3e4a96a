# Sourced by the end-to-end scripts test/check_*.sh: strict mode, a scratch
# directory removed at exit ($work), fail(), the Python that sees Debian's
# modules ($py), DESIGN.md's report-schema checker ($schema) and
# report_field, which reads one value out of a JSON report.
set -uo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
py=/usr/bin/python3
[[ -x $py ]] || py=python3
schema="$(dirname "${BASH_SOURCE[0]}")/check_report_schema.py"

# report_field FILE TOOL KEY [NAME=VALUE ...]: the KEY of the one case of the
# report FILE, written by TOOL, whose fields NAME all equal VALUE.
report_field() {
  "$py" -c 'import json, sys
r = json.load(open(sys.argv[1]))
assert r["tool"] == sys.argv[2], r["tool"]
want = dict(a.split("=", 1) for a in sys.argv[4:])
c = [c for c in r["cases"] if all(str(c.get(k)) == v for k, v in want.items())]
assert len(c) == 1, (want, len(c))
print(c[0][sys.argv[3]])' "$@"
}
