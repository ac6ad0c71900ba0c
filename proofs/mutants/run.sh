#!/usr/bin/env bash
# Mutation evidence for pacs-proofs: apply each known bug (proofs/mutants/*.patch) to a scratch
# copy of the tree, run the harness twins and unit tests (`cargo test -p pacs-proofs -p pacs-reach
# --lib`: the harnesses of compositions and those beside the code), record which
# fail (= catch the mutant), revert, and print a Markdown table. Exit status 1 if any mutant
# survives or a patch no longer applies.
#
# Usage: proofs/mutants/run.sh [name-filter]
# Env:   MUTANT_WORKDIR     scratch copy of the tree   (default /tmp/pacs-mutants)
#        CARGO_TARGET_DIR   build dir for the mutants   (default /work/target-proofs-mutants)
#        PACS_PROOFS_CASES  cases per harness twin      (default 10000, as in CI)
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${MUTANT_WORKDIR:-/tmp/pacs-mutants}
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/work/target-proofs-mutants}
export PACS_PROOFS_CASES=${PACS_PROOFS_CASES:-10000}
filter=${1:-}

rm -rf "$work" && mkdir -p "$work"
tar -C "$root" --exclude=./.git --exclude=./target -cf - . | tar -C "$work" -xf -
cd "$work" || exit 2
# Newer than any artifact in the target dir (which may hold a previous run's mutant builds):
# cargo must rebuild from these sources, not trust copied modification times.
find . -name '*.rs' -exec touch {} +

# Baseline: every harness must pass on the unmutated tree.
if ! cargo test -q -p pacs-proofs -p pacs-reach --lib >"$work/baseline.log" 2>&1; then
    echo "baseline fails; see $work/baseline.log" >&2
    exit 2
fi

status=0
printf '| mutant | caught by (failing harness twins) |\n|---|---|\n'
for patch in "$root"/proofs/mutants/*.patch; do
    name=$(basename "$patch" .patch)
    [[ -n "$filter" && "$name" != *"$filter"* ]] && continue
    if ! patch -s -p1 <"$patch"; then
        printf '| %s | PATCH DOES NOT APPLY |\n' "$name"
        status=1
        continue
    fi
    log="$work/$name.log"
    cargo test -p pacs-proofs -p pacs-reach --lib --no-fail-fast >"$log" 2>&1
    # The shield's and the audit's object scenarios (the object rule has no harness of its own yet).
    cargo test -p pacs-shield --test objects --no-fail-fast >>"$log" 2>&1
    cargo test -p pacs-audit --test audit_objects --no-fail-fast >>"$log" 2>&1
    # The object rule's decision-only mode (x43: the box test inverted).
    cargo test -p pacs-verify --test object_rule --no-fail-fast >>"$log" 2>&1
    # The audit's span checks with a person (x74: a pair cleared by a measurement reporting it).
    cargo test -p pacs-audit --test audit_checks --no-fail-fast >>"$log" 2>&1
    # The audit's input-consistency checks (x20: a human faster than the model).
    cargo test -p pacs-audit --test audit_consistency --no-fail-fast >>"$log" 2>&1
    # Several people, logs cut short, stamps that cannot resolve the samples (x60–x64).
    cargo test -p pacs-audit --test audit_people --no-fail-fast >>"$log" 2>&1
    # MCAP: a given header keeps the file's own promises (x114).
    cargo test -p pacs-audit --test audit_mcap --no-fail-fast >>"$log" 2>&1
    # ROS 2 bags: the metadata's counts, other logs in a bag directory, a lone part (x93–x95).
    cargo test -p pacs-audit --test audit_db3 --no-fail-fast >>"$log" 2>&1
    # The human-record consistency check's box accept (x66).
    cargo test -p pacs-audit --lib --no-fail-fast >>"$log" 2>&1
    # The block fast path against span by span, objects included (x65).
    cargo test -p pacs-audit --test audit_blocks --no-fail-fast >>"$log" 2>&1
    # The planner's checked stopping tail of Moving chunks (x21).
    cargo test -p pacs-motion --test trajectory --no-fail-fast >>"$log" 2>&1
    # The path-speed limits' derivative windows (x44: pieces cut by the window left out).
    cargo test -p pacs-motion --test properties derivative_bounds --no-fail-fast >>"$log" 2>&1
    # Chunks planned off the loop and taken over at their handover (x22).
    cargo test -p pacs-shield --test handover --no-fail-fast >>"$log" 2>&1
    # The planning thread's predictions and re-plans (x49, x50).
    cargo test -p pacs-shield --test worker --no-fail-fast >>"$log" 2>&1
    # Capsules fitted to collision meshes (x24).
    cargo test -p pacs-mesh --test mesh --no-fail-fast >>"$log" 2>&1
    # The path ranges next to phase boundaries (x26).
    cargo test -p pacs-motion --lib --no-fail-fast >>"$log" 2>&1
    # The user-scene runner's log (x55: only the newest measurement of a step logged).
    cargo test -p pacs --test cli_shield --no-fail-fast >>"$log" 2>&1
    cargo test -p pacs-shield --lib --no-fail-fast >>"$log" 2>&1
    # The shield's person and object measurements held against the trusted ones (x118–x120;
    # the objects' test runs with `pacs-shield --test objects` above).
    cargo test -p pacs-shield --test shield --no-fail-fast >>"$log" 2>&1
    # An object's velocity beyond its speed bound (x117).
    cargo test -p pacs-reach --test object --no-fail-fast >>"$log" 2>&1
    # The pos model's consistency test at the limit (x27).
    cargo test -p pacs-reach --test human_occupancy --no-fail-fast >>"$log" 2>&1
    caught=$(sed -n 's/^test \(.*\) \.\.\. FAILED$/\1/p' "$log" |
        sed 's/::property_test$//; s/^.*:://' | sort | paste -sd, - | sed 's/,/, /g')
    if grep -q '^error\(\[E[0-9]*\]\)\?:' "$log" && [[ -z "$caught" ]]; then
        caught="BUILD FAILED"
        status=1
    elif [[ -z "$caught" ]]; then
        caught="**SURVIVED**"
        status=1
    fi
    printf '| %s | %s |\n' "$name" "$caught"
    patch -s -R -p1 <"$patch"
done
exit $status
