#!/usr/bin/env bash
# Model-check the Kani harnesses of pacs (`cargo kani -p PACKAGE --lib`: pacs-proofs and the proofs
# beside the code in pacs-reach), one CBMC run per harness, and print a table: harness, result,
# CBMC time.
#
#   bash proofs/kani.sh                 # the harnesses listed in proofs/kani-ci.txt, each with its solver
#   bash proofs/kani.sh a1_add_enclose f2_occupancy_intervals_cover   # these (KANI_SOLVER=bitwuzla|sat)
#
# Exit status: 0 if every harness run verified, 1 if any failed or timed out, 0 with one line of
# explanation if `cargo kani` is not installed (then nothing was model-checked; CI still runs the
# property-test twins and the `kani_stub` type-check). KANI_HARNESS_TIMEOUT (s, default 600) bounds
# each harness; the README's budget is 120 s on a 2-core machine, the default leaves room for a
# loaded one. KANI_JOBS (default: the machine's cores) harnesses run at once, one core each.
set -uo pipefail
cd "$(dirname "$0")/.."

if ! cargo kani --version >/dev/null 2>&1; then
  echo "proofs: cargo kani is not installed here: the harnesses were NOT model-checked (their property-test twins ran under cargo test)"
  exit 0
fi

timeout_s="${KANI_HARNESS_TIMEOUT:-600}"
target_dir="${CARGO_TARGET_DIR:-target}"
log_dir="$target_dir/kani-logs"
mkdir -p "$log_dir"
echo "proofs: $(cargo kani --version 2>/dev/null | head -n1)"

# The harnesses to model-check, each with its decision procedure: the arguments (solver from
# KANI_SOLVER, default bitwuzla), else every line `harness solver` of proofs/kani-ci.txt (the
# harnesses that verify within the budget; the README's table gives the others and why).
#   sat:      CBMC's built-in SAT back end (CaDiCaL), CBMC's own bit-precise float encoding;
#   bitwuzla: CBMC's SMT back end with the floating-point theory, solved by Bitwuzla (10-40x
#             faster on float claims; see proofs/README.md, "Solvers", for what it trusts).
# Harnesses sit beside the code they check (`mod proofs` in a crate's src/, e.g. pacs-reach's
# rounding and interval) or, for compositions, in proofs/src/harnesses (pacs-proofs): every
# source file with a `harness!(` invocation or a plain `#[kani::proof]`, and the package each
# harness is compiled in.
mapfile -t harness_files < <(grep -rlE --include='*.rs' --exclude-dir=target --exclude-dir=kit '^harness!\(|^#\[kani::proof\]' . | sort)
package_of() {
  local file dir
  file=$(grep -lE "^    $1,\$|^(pub )?fn $1\(\)" "${harness_files[@]}" | head -n1)
  [ -z "$file" ] && return 1
  dir=${file%%/src/*}
  sed -n 's/^name = "\(.*\)"/\1/p' "$dir/Cargo.toml" | head -n1
}
declare -A solver_of=()
declare -A package_of_h=()
selected=()
if [ "$#" -gt 0 ]; then
  for h in "$@"; do selected+=("$h"); solver_of[$h]="${KANI_SOLVER:-bitwuzla}"; done
else
  while read -r h solver _; do
    selected+=("$h")
    solver_of[$h]="${solver:-sat}"
  done < <(grep -vE '^\s*(#|$)' proofs/kani-ci.txt)
  mapfile -t all < <(grep -rh -A1 '^harness!(' "${harness_files[@]}" | grep -oE '^\s+[a-z][a-z0-9_]+,' | tr -d ' ,' | sort)
  for h in "${all[@]}"; do
    if [ -z "${solver_of[$h]:-}" ]; then
      if grep -h -A2 "^    $h,\$" "${harness_files[@]}" | grep -q twin_only; then
        echo "proofs: $h: property test only (README: what its proofs cover)"
      else
        echo "proofs: $h: not model-checked here (not in proofs/kani-ci.txt: not yet verified within the 120 s budget; README's harness table)"
      fi
    fi
  done
fi

# Bitwuzla: PyPI ships its Python bindings, not a binary; proofs/smt/bitwuzla_cli.py is the
# `bitwuzla` command CBMC calls, run in a venv under the target directory.
need_bitwuzla=0
for h in "${selected[@]}"; do [ "${solver_of[$h]}" = bitwuzla ] && need_bitwuzla=1; done
if [ "$need_bitwuzla" = 1 ]; then
  smt_dir="$target_dir/kani-smt"
  if ! "$smt_dir/venv/bin/python" -c 'import bitwuzla' >/dev/null 2>&1; then
    python3 -m venv "$smt_dir/venv" >/dev/null 2>&1 &&
      "$smt_dir/venv/bin/pip" install -q "bitwuzla==${BITWUZLA_VERSION:-0.10.0}" >/dev/null 2>&1
  fi
  if "$smt_dir/venv/bin/python" -c 'import bitwuzla' >/dev/null 2>&1; then
    mkdir -p "$smt_dir/bin"
    printf '#!/bin/sh\nexec "%s" "%s" "$@"\n' "$(cd "$smt_dir/venv/bin" && pwd)/python" \
      "$(pwd)/proofs/smt/bitwuzla_cli.py" >"$smt_dir/bin/bitwuzla"
    chmod +x "$smt_dir/bin/bitwuzla"
    PATH="$(cd "$smt_dir/bin" && pwd):$PATH"
    export PATH
    echo "proofs: Bitwuzla $("$smt_dir/venv/bin/pip" show bitwuzla 2>/dev/null | sed -n 's/^Version: //p') from PyPI (CBMC's SMT back end, floating-point theory)"
  else
    echo "proofs: Bitwuzla could not be installed (pip): those harnesses run on CBMC's SAT back end (slower; may exceed the budget)"
    for h in "${selected[@]}"; do solver_of[$h]=sat; done
  fi
fi

for h in "${selected[@]}"; do
  if ! package_of_h[$h]=$(package_of "$h") || [ -z "${package_of_h[$h]}" ]; then
    echo "proofs: $h: no such harness (no \`harness!(\` defines it)"
    exit 1
  fi
done
mapfile -t packages < <(printf '%s\n' "${package_of_h[@]}" | sort -u)

# KANI_JOBS harnesses at once (default: the machine's cores; each CBMC run is one process on one
# core). The harnesses are run per package and solver, one such group after the other (the two
# solvers build a package with different flags — `--no-assertion-reach-checks` — so two groups
# of one package must never build or read the same target directory at once), each group by ONE
# `cargo kani` that checks its harnesses KANI_JOBS at a time (Kani's `--jobs`, which needs the
# terse output format). One invocation, not several side by side: every `cargo kani` links the
# goto binary of every harness of the package into the shared target directory before it
# checks any, and instruments a harness's binary in place before CBMC reads it, so a second
# invocation would rewrite binaries the first is reading (a truncated goto binary) or has
# just instrumented (a binary checked without its instrumentation). With `--jobs` each line of
# the log a thread starts is prefixed `Thread N: `; the table below follows each thread's lines.
log="${PACS_KANI_LOG:-$log_dir/kani.log}"  # PACS_KANI_LOG: another file, for runs side by side
: >"$log"
if [ "${#selected[@]}" -eq 0 ]; then
  echo "proofs: no harness selected (proofs/kani-ci.txt lists none)"
  exit 1
fi
jobs_n="${KANI_JOBS:-$(nproc 2>/dev/null || echo 1)}"
[[ "$jobs_n" =~ ^[1-9][0-9]{0,3}$ ]] || { echo "proofs: KANI_JOBS must be an integer from 1 to 9999, not '$jobs_n'"; exit 1; }
echo "proofs: ${#selected[@]} harnesses, up to $jobs_n at a time (KANI_JOBS)"
code=0
for package in "${packages[@]}"; do
for solver in sat bitwuzla; do
  args=()
  for h in "${selected[@]}"; do
    [ "${solver_of[$h]}" = "$solver" ] && [ "${package_of_h[$h]}" = "$package" ] && args+=(--harness "$h")
  done
  [ "${#args[@]}" -eq 0 ] && continue
  extra=()
  # Bitwuzla runs as a fresh process per query (no incremental solving): without the
  # reachability checks of every assertion, a proof is one `unsat` query instead of one query
  # per reachable assertion. Their role (no assertion vacuously unreachable) is played by the
  # mutants caught and by the property-test twins (proofs/README.md, "Solvers").
  [ "$solver" = bitwuzla ] && extra=(--no-assertion-reach-checks --cbmc-args --bitwuzla)
  parallel=()
  [ "$jobs_n" -gt 1 ] && parallel=(--jobs "$jobs_n" --output-format terse)
  echo "=== solver $solver package $package" >>"$log"
  timeout --kill-after=10 "${KANI_TOTAL_TIMEOUT:-4800}" \
    cargo kani -p "$package" --lib "${args[@]}" "${parallel[@]}" \
    -Z unstable-options -Z stubbing -Z function-contracts --harness-timeout "${timeout_s}s" "${extra[@]}" >>"$log" 2>&1 || code=$?
done
done

# Per harness: its result and CBMC time, from the log.
# With `--jobs`, a thread's lines start `Thread N: `: `Thread N: Checking harness X...` starts
# X on thread N, and a later `Thread N: ...` line starts X's result block (printed at once), to
# which the unprefixed lines after it belong.
awk '
  /^=== solver / { solver = $3; name = "" }
  /^Thread [0-9]+: / { th = $2; sub(/:$/, "", th); sub(/^Thread [0-9]+: /, ""); if ($0 !~ /^Checking harness /) name = on[th] }
  /^Checking harness / { h = $3; sub(/\.\.\.$/, "", h); n = split(h, p, "::"); name = p[n]; on[th] = name; th = ""; res[name] = "ERROR"; sol[name] = solver; order[++k] = name }
  /VERIFICATION:- SUCCESSFUL/ { res[name] = "SUCCESSFUL" }
  /VERIFICATION:- FAILED/ { res[name] = "FAILED" }
  /[Tt]imed out|TIMEOUT/ { if (name != "") res[name] = "TIMEOUT" }
  /Verification Time: / { t = $3; sub(/s$/, "", t); tm[name] = t }
  END {
    printf "%-46s %-9s %-12s %10s\n", "harness", "solver", "result", "CBMC s"
    for (i = 1; i <= k; i++) printf "%-46s %-9s %-12s %10s\n", order[i], sol[order[i]], res[order[i]], tm[order[i]]
  }' "$log"
# Every selected harness checked exactly once and verified: the names, not only their count
# (a `--harness` filter that matches nothing is ignored by Kani without an error).
wanted=$(printf '%s\n' "${selected[@]}" | sort -u)
checked=$(sed -n 's/^\(Thread [0-9]*: \)\{0,1\}Checking harness \(.*::\)\{0,1\}\([a-z0-9_]*\)\.\.\.$/\3/p' "$log" | sort)
verified=$(awk '
  /^Thread [0-9]+: / { th = $2; sub(/:$/, "", th); sub(/^Thread [0-9]+: /, ""); if ($0 !~ /^Checking harness /) name = on[th] }
  /^Checking harness / { h = $3; sub(/\.\.\.$/, "", h); n = split(h, p, "::"); name = p[n]; on[th] = name; th = "" }
  /VERIFICATION:- SUCCESSFUL/ { print name }' "$log" | sort)
if [ "$code" -ne 0 ] || [ "$checked" != "$wanted" ] || [ "$verified" != "$wanted" ] ||
  grep -q 'VERIFICATION:- FAILED' "$log"; then
  grep -E 'Failed Checks:|^error' "$log" | head -n 20 | sed 's/^/    /'
  [ "$checked" != "$wanted" ] && diff <(echo "$wanted") <(echo "$checked") | sed -n 's/^[<>] /    harness checked not exactly once: /p'
  echo "proofs: not every harness verified (exit $code; full log: $log)"
  exit 1
fi
echo "proofs: all ${#selected[@]} harnesses VERIFICATION SUCCESSFUL (full log: $log)"
