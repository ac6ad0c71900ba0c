#!/usr/bin/env python3
"""Keep proofs/README.md's harness table true to the code and to proofs/kani-ci.txt.

    python3 proofs/claims.py            # check; exit 1 with one line per disagreement
    python3 proofs/claims.py --table    # also print the claims table (claim -> harnesses)

What it checks (CI runs it; it needs no Kani):
- every harness in the code (`harness!(NAME, ...)` in a proofs module or pacs-proofs, or a
  `#[kani::proof]` / `#[kani::proof_for_contract(...)]` function) has a row in the README's
  harness table, and every name in the table is a harness in the code;
- every harness listed in proofs/kani-ci.txt exists, is model-checked (not `twin_only`), and its
  row says `**SUCCESSFUL** (CI, ...`; every row that says so is listed in kani-ci.txt;
- every `twin_only` harness's row says it is a property test only, with a reason (text after
  "only", or a Kani attempt in parentheses), and the twin-only count is printed;
- every row names at least one claim (C1-C9, C4', C8', solver).
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "proofs" / "README.md"
CI_LIST = ROOT / "proofs" / "kani-ci.txt"
SKIP_DIRS = {"target", "kit", ".git", "fuzz", "kani-stub"}


def source_files():
    for p in ROOT.rglob("*.rs"):
        if SKIP_DIRS.intersection(p.relative_to(ROOT).parts):
            continue
        yield p


def code_harnesses():
    """name -> (file, twin_only) for every harness in the code."""
    found = {}
    for p in source_files():
        text = p.read_text(encoding="utf-8")
        if "harness!(" not in text and "kani::proof" not in text:
            continue
        rel = str(p.relative_to(ROOT))
        for m in re.finditer(r"^harness!\(\s*\n\s*([a-z][a-z0-9_]*),(.*?)\n\);", text, re.M | re.S):
            found[m.group(1)] = (rel, "twin_only" in m.group(2))
        for m in re.finditer(
            r"^#\[kani::proof(?:_for_contract\([^)]*\))?\]\n(?:#\[[^\n]*\]\n)*(?:pub )?fn ([a-z][a-z0-9_]*)\(",
            text,
            re.M,
        ):
            found.setdefault(m.group(1), (rel, False))
    return found


def table_rows():
    """(names, claims, result, line number) per row of the harness table."""
    rows = []
    lines = README.read_text(encoding="utf-8").splitlines()
    start = next(
        (i for i, l in enumerate(lines) if l.startswith("| harness (twin")), None
    )
    if start is None:
        sys.exit("proofs/claims.py: README.md has no harness table ('| harness (twin ...')")
    for i in range(start + 2, len(lines)):
        line = lines[i]
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 6:
            rows.append(([], "", "", i + 1))
            continue
        names = re.findall(r"`([a-z][a-z0-9_]*)`", cells[0])
        rows.append((names, cells[1], cells[4], i + 1))
    return rows


def ci_list():
    out = []
    for line in CI_LIST.read_text(encoding="utf-8").splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            out.append(line.split()[0])
    return out


def main():
    problems = []
    code = code_harnesses()
    rows = table_rows()
    ci = ci_list()
    in_table = {}
    for names, claim, result, ln in rows:
        if not names:
            problems.append(f"README.md:{ln}: a table row names no harness")
        if not re.search(r"C[1-9]|solver", claim):
            problems.append(f"README.md:{ln}: row {names} names no claim (C1-C9, C4', C8', solver)")
        for n in names:
            in_table[n] = (result, ln)
    for n, (f, twin) in sorted(code.items()):
        if n not in in_table:
            problems.append(f"{f}: harness {n} has no row in proofs/README.md's harness table")
    plain = set()
    all_text = "\n".join(p.read_text(encoding="utf-8") for p in source_files())
    for n, (_, ln) in sorted(in_table.items()):
        if n in code:
            continue
        if re.search(rf"\bfn {n}\(", all_text):
            # A plain property test the table lists as a harness (no Kani body).
            code[n] = ("(property test)", True)
            plain.add(n)
        else:
            problems.append(f"README.md:{ln}: {n} is not a harness in the code")
    for n in ci:
        if n not in code:
            problems.append(f"kani-ci.txt: {n} is not a harness in the code")
            continue
        if code[n][1]:
            problems.append(f"kani-ci.txt: {n} is twin_only (not model-checked) in {code[n][0]}")
        res = in_table.get(n, ("", 0))[0]
        if not res.startswith("**SUCCESSFUL** (CI"):
            problems.append(f"README.md: {n} is in kani-ci.txt but its row does not say '**SUCCESSFUL** (CI, ...'")
    for n, (res, ln) in sorted(in_table.items()):
        if res.startswith("**SUCCESSFUL** (CI") and n not in ci:
            problems.append(f"README.md:{ln}: {n} says verified in CI but is not in kani-ci.txt")
    twin_only = sorted(n for n, (_, t) in code.items() if t and n not in plain)
    for n in twin_only + sorted(plain):
        res = in_table.get(n, ("", 0))[0]
        if n in in_table and not re.match(r"property tests? only\S*\s*\S", res):
            problems.append(
                f"README.md:{in_table[n][1]}: twin-only {n} must say 'property test only' and why"
            )
    if "--table" in sys.argv:
        claims = {}
        for names, claim, result, _ in rows:
            for c in re.findall(r"C[1-9]′?|solver", claim):
                for n in names:
                    kind = "Kani (CI)" if n in ci else ("twin only" if code.get(n, ("", False))[1] else "Kani (not CI)")
                    claims.setdefault(c, []).append((n, kind))
        for c in sorted(claims):
            print(f"{c}:")
            for n, kind in claims[c]:
                print(f"  {kind:14} {n}")
    for p in problems:
        print(f"proofs/claims.py: {p}")
    print(
        f"proofs/claims.py: {len(code)} harnesses, {len(ci)} model-checked in CI, "
        f"{len(twin_only)} twin-only harness bodies, {len(plain)} plain property tests; "
        f"{len(problems)} disagreements"
    )
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
