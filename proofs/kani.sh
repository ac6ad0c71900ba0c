#!/usr/bin/env bash
# Model-check every Kani harness of pacs (`cargo kani -p pacs-proofs`), one CBMC run per harness,
# and print a table: harness, result, CBMC time.
#
#   bash proofs/kani.sh                 # the harnesses listed in proofs/kani-ci.txt
#   bash proofs/kani.sh a1_add_enclose f2_occupancy_intervals_cover   # these
#
# Exit status: 0 if every harness run verified, 1 if any failed or timed out, 0 with one line of
# explanation if `cargo kani` is not installed (then nothing was model-checked; CI still runs the
# property-test twins and the `kani_stub` type-check). KANI_HARNESS_TIMEOUT (s, default 300) bounds
# each harness; the README's budget is 120 s on an idle 2-core machine, the default leaves room
# for a loaded one.
set -uo pipefail
cd "$(dirname "$0")/.."

if ! cargo kani --version >/dev/null 2>&1; then
  echo "proofs: cargo kani is not installed here: the harnesses were NOT model-checked (their property-test twins ran under cargo test)"
  exit 0
fi

timeout_s="${KANI_HARNESS_TIMEOUT:-300}"
log_dir="${CARGO_TARGET_DIR:-target}/kani-logs"
mkdir -p "$log_dir"
echo "proofs: $(cargo kani --version 2>/dev/null | head -n1)"

# The harnesses to model-check: the arguments, else every one listed in proofs/kani-ci.txt (the
# harnesses that verify within the budget; the README's table gives the others and why).
if [ "$#" -gt 0 ]; then
  selected=("$@")
else
  mapfile -t selected < <(grep -vE '^\s*(#|$)' proofs/kani-ci.txt)
  mapfile -t all < <(grep -rh -A1 '^harness!(' proofs/src/harnesses | grep -oE '^\s+[a-z][a-z0-9_]+,' | tr -d ' ,' | sort)
  for h in "${all[@]}"; do
    if ! printf '%s\n' "${selected[@]}" | grep -qx "$h"; then
      if grep -A2 "^    $h,\$" proofs/src/harnesses/*.rs | grep -q twin_only; then
        echo "proofs: $h: property test only (README: what its proofs cover)"
      else
        echo "proofs: $h: not model-checked here (not in proofs/kani-ci.txt: not yet verified within the 120 s budget; README's harness table)"
      fi
    fi
  done
fi
# One cargo kani run compiles once and checks the selected harnesses one after the other.
args=()
for h in "${selected[@]}"; do args+=(--harness "$h"); done
log="$log_dir/kani.log"
timeout --kill-after=10 "${KANI_TOTAL_TIMEOUT:-4800}" \
  cargo kani -p pacs-proofs --lib "${args[@]}" \
  -Z unstable-options --harness-timeout "${timeout_s}s" >"$log" 2>&1
code=$?

# Per harness: its result and CBMC time, from the log.
awk '
  /^Checking harness / { h = $3; sub(/\.\.\.$/, "", h); n = split(h, p, "::"); name = p[n]; res[name] = "ERROR"; order[++k] = name }
  /VERIFICATION:- SUCCESSFUL/ { res[name] = "SUCCESSFUL" }
  /VERIFICATION:- FAILED/ { res[name] = "FAILED" }
  /[Tt]imed out|TIMEOUT/ { if (name != "") res[name] = "TIMEOUT" }
  /Verification Time: / { t = $3; sub(/s$/, "", t); tm[name] = t }
  END {
    printf "%-46s %-12s %10s\n", "harness", "result", "CBMC s"
    for (i = 1; i <= k; i++) printf "%-46s %-12s %10s\n", order[i], res[order[i]], tm[order[i]]
  }' "$log"
grep -E '^Complete - |^Summary' -A0 "$log" | tail -n 1
if [ "$code" -ne 0 ] || ! grep -q '^Complete - ' "$log" || grep -q 'VERIFICATION:- FAILED' "$log"; then
  grep -E 'Failed Checks:|^error' "$log" | head -n 20 | sed 's/^/    /'
  echo "proofs: not every harness verified (exit $code; full log: $log)"
  exit 1
fi
echo "proofs: every harness VERIFICATION SUCCESSFUL (full log: $log)"
