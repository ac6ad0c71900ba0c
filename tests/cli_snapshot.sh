#!/usr/bin/env bash
# Snapshot of the CLI's observable output (stdout, stderr, exit code, written files) on the shipped
# examples and `pacs demo`, for byte-identity checks across refactors:
#
#   bash tests/cli_snapshot.sh OUT_DIR [PACS_BINARY]      # default binary: target/release/pacs
#   diff -r before/ after/      # compare two snapshots (reports name the git revision: it differs)
set -u
out=$1
bin=${2:-$(pwd)/target/release/pacs}
root=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$out" && mkdir -p "$out"
out=$(cd "$out" && pwd)
work=$(mktemp -d)
cp -r "$root/examples" "$work/"
run() {
  local name=$1
  shift
  (cd "$work" && "$bin" "$@" >"$out/$name.out" 2>"$out/$name.err"; echo $? >"$out/$name.rc")
}
run demo demo
run reach_human reach human
run reach_robot reach robot
run robot_show robot show fr3
run human_show human show default
run fk fk --input examples/robot.json
run audit_clean audit examples/logs/clean_sorting.jsonl --out rep1
run audit_close audit examples/logs/close_sorting.jsonl --out rep2 --json
run audit_both audit examples/logs/clean_sorting.jsonl examples/logs/close_sorting.jsonl
run help --help
run trajectory_help trajectory --help
(cd "$work" && find rep1 rep2 pacs-out -type f | sort | while read -r f; do
  mkdir -p "$out/files/$(dirname "$f")"
  cp "$f" "$out/files/$f"
done)
rm -rf "$work"
echo "snapshot in $out"
