#!/usr/bin/env python3
"""A `bitwuzla` command for `cbmc --bitwuzla`, over Bitwuzla's Python bindings (PyPI `bitwuzla`).

CBMC runs `bitwuzla FILE` and reads the SMT-LIB2 answers (`sat`/`unsat`, then `get-value`
results) from standard output. Bitwuzla ships no command-line binary on PyPI; this script is that
command: it reads FILE, repairs the sorts of floating-point terms that CBMC flattens into
bit-vectors (see `repair_float_sorts`), and executes every command with Bitwuzla's parser, which
prints the answers as the Bitwuzla binary would.

Why it is sound to use for proofs: the repair only ever *adds* freedom (a NaN float may stand for
any NaN bit pattern; every non-NaN float keeps exactly its bits), so an `unsat` answer on the
repaired problem implies `unsat` on CBMC's; the mutants in proofs/README.md show that failures
are still found.
"""
import os
import re
import sys

FP_LITERAL = re.compile(r"\(fp #b([01]+) #b([01]+) #b([01]+)\)")
# Special float literals with exactly one bit pattern each (NaN has many: not rewritten).
FP_SPECIAL = re.compile(r"\(_ (\+oo|-oo|\+zero|-zero) (\d+) (\d+)\)")


def special_bits(kind: str, e: int, s: int) -> str:
    """The IEEE 754 bits of `(_ kind e s)` (±oo, ±zero): sign, exponent, significand."""
    sign = "1" if kind.startswith("-") else "0"
    exponent = ("1" if kind.endswith("oo") else "0") * e
    return sign + exponent + "0" * (s - 1)
FP_SYMBOL = re.compile(
    r"^\((?:declare-fun|define-fun) (\|[^|]*\||[^\s()]+) \(\) \(_ FloatingPoint (\d+) (\d+)\)",
    re.M,
)
BV_DEFINITION = re.compile(
    r"^\(define-fun (\|[^|]*\||[^\s()]+) \(\) \(_ BitVec (\d+)\) (\|[^|]*\||\(fp #b[01]+ #b[01]+ #b[01]+\))\)$",
    re.M,
)
BV_SYMBOL = re.compile(
    r"^\((?:declare-fun|define-fun) (\|[^|]*\||[^\s()]+) \(\) \(_ BitVec \d+\)", re.M
)
FP_DEFINITION = re.compile(
    r"^\(define-fun (\|[^|]*\||[^\s()]+) \(\) \(_ FloatingPoint (\d+) (\d+)\) (.*)\)$", re.M
)
EQUATION = re.compile(
    r"^\(assert \(= (\|[^|]*\||[^\s()]+) (\|[^|]*\||[^\s()]+)\)\)$", re.M
)
# Operators whose arguments must be bit-vectors but to which CBMC passes floats (the flattening
# of structs and enum payloads that contain an f64).
BIT_VECTOR_OPERATORS = {"concat"}


def repair_float_sorts(text: str) -> str:
    """Return `text` with every float argument of a bit-vector operator made a bit-vector.

    - a float literal `(fp #bS #bE #bM)` becomes the literal `#bSEM` (the same IEEE 754 bits),
      and so do `(_ +oo E S)`, `(_ -oo E S)`, `(_ +zero E S)`, `(_ -zero E S)` (one bit pattern
      each; `NaN` literals are left alone: they have many);
    - a float symbol `X` becomes a fresh bit-vector symbol `X__bv` with the constraint
      `((_ to_fp E M) X__bv) = X` (exactly X's bits unless X is NaN, then any NaN's bits);
    - the same for a bit-vector definition whose whole body is a float symbol or literal;
    - a float definition whose body is a bit-vector (`extract`, bit-vector symbol) reads its
      bits with `to_fp` (the IEEE 754 reinterpretation, exact up to NaN payloads);
    - an equation between a float symbol and a bit-vector symbol compares the float's twin.
    """
    float_symbols = {m.group(1): (int(m.group(2)), int(m.group(3))) for m in FP_SYMBOL.finditer(text)}
    twins = {}

    # A bit-vector definition whose whole body is a float symbol or literal.
    def bv_body(m):
        name, width, body = m.group(1), int(m.group(2)), m.group(3)
        lit = FP_LITERAL.fullmatch(body)
        if lit and sum(len(g) for g in lit.groups()) == width:
            return "(define-fun %s () (_ BitVec %d) #b%s)" % (name, width, "".join(lit.groups()))
        if body in float_symbols and sum(float_symbols[body]) == width:
            twins[body] = body[:-1] + "__bv|"
            return "(define-fun %s () (_ BitVec %d) %s)" % (name, width, twins[body])
        return m.group(0)

    text = BV_DEFINITION.sub(bv_body, text)

    # A float definition whose body is a bit-vector (an `extract` from a flattened struct or
    # array element, or a bit-vector symbol): read the bits as the float (`to_fp` of a
    # bit-vector is the IEEE 754 reinterpretation).
    bv_symbols = {m.group(1) for m in BV_SYMBOL.finditer(text)}

    def fp_body(m):
        name, e, sig, body = m.group(1), m.group(2), m.group(3), m.group(4)
        if body.startswith("((_ extract ") or body in bv_symbols:
            return "(define-fun %s () (_ FloatingPoint %s %s) ((_ to_fp %s %s) %s))" % (
                name, e, sig, e, sig, body)
        return m.group(0)

    text = FP_DEFINITION.sub(fp_body, text)

    # An equation between a float symbol and a bit-vector symbol: compare the bits.
    def mixed_equation(m):
        a, b = m.group(1), m.group(2)
        if a in float_symbols and b in bv_symbols:
            twins[a] = a[:-1] + "__bv|"
            return "(assert (= %s %s))" % (twins[a], b)
        if b in float_symbols and a in bv_symbols:
            twins[b] = b[:-1] + "__bv|"
            return "(assert (= %s %s))" % (a, twins[b])
        return m.group(0)

    text = EQUATION.sub(mixed_equation, text)
    out = []
    last = 0
    operators = []  # operator of every open list ('(' for a list starting with a list)
    i = 0
    n = len(text)
    while i < n:
        c = text[i]
        in_bv_op = bool(operators) and operators[-1] in BIT_VECTOR_OPERATORS
        if c == "(":
            if in_bv_op and text.startswith("(fp #b", i):
                m = FP_LITERAL.match(text, i)
                if m:
                    out.append(text[last:i])
                    out.append("#b" + m.group(1) + m.group(2) + m.group(3))
                    i = last = m.end()
                    continue
            if in_bv_op and text.startswith("(_ ", i):
                m = FP_SPECIAL.match(text, i)
                if m:
                    out.append(text[last:i])
                    out.append("#b" + special_bits(m.group(1), int(m.group(2)), int(m.group(3))))
                    i = last = m.end()
                    continue
            j = i + 1
            if j < n and text[j] == "(":
                operators.append("(")
            else:
                k = j
                while k < n and text[k] not in " ()\n":
                    k += 1
                operators.append(text[j:k])
            i += 1
        elif c == ")":
            if operators:
                operators.pop()
            i += 1
        elif c == "|":
            k = text.index("|", i + 1) + 1
            name = text[i:k]
            if in_bv_op and name in float_symbols:
                twin = name[:-1] + "__bv|"
                twins[name] = twin
                out.append(text[last:i])
                out.append(twin)
                last = k
            i = k
        elif c == '"':
            i = text.index('"', i + 1) + 1
        elif c == ";":
            k = text.find("\n", i)
            i = n if k < 0 else k
        else:
            i += 1
    out.append(text[last:])
    result = zero_width_unused(text="".join(out))
    if not twins:
        return result
    declarations = "".join(
        "(declare-fun %s () (_ BitVec %d))\n" % (twin, sum(float_symbols[name]))
        for name, twin in twins.items()
    )
    links = "".join(
        "(assert (= ((_ to_fp %d %d) %s) %s))\n" % (*float_symbols[name], twin, name)
        for name, twin in twins.items()
    )
    first = min(p for p in (result.find("\n(declare-fun"), result.find("\n(define-fun")) if p >= 0)
    result = result[: first + 1] + declarations + result[first + 1 :]
    check = result.find("(check-sat")
    if check < 0:
        return result + links
    return result[:check] + links + result[check:]


# CBMC 6.4's SMT2 back end (without datatypes, as for Bitwuzla) builds the `overflow_result`
# struct of signed `+`/`−` and of `×` (Rust's `*_with_overflow`, behind every checked integer
# operation) as `(concat RESULT FLAG)`, i.e. the flag in bit 0, but reads the members back with
# the struct layout it uses everywhere else (first member, the result, in the low bits; the flag
# above it: `((_ extract W W) s)`), as its own unsigned `+`/`−` case builds it (`?sum`, carry on
# top). Unrepaired, the flag reads the result's sign bit and the result is shifted by one bit:
# `biased - 1075` "overflows" for every float below 2 (found with a harness on `Dyadic::of`).
OVERFLOW_RESULTS = [
    # signed + and −
    re.compile(
        r"\(concat \(\(_ extract (\d+) 0\) \?sum\) \(ite "
        r"(\(not \(= \(\(_ extract \d+ \d+\) \?sum\) \(\(_ extract \d+ \d+\) \?sum\)\)\)) "
        r"#b1 #b0\)\)"
    ),
    # signed ×
    re.compile(
        r"\(concat \(\(_ extract (\d+) 0\) prod\) \(ite "
        r"(\(or \(bvsge prod \(_ bv\d+ \d+\)\) \(bvslt prod \(bvneg \(_ bv\d+ \d+\)\)\)\)) "
        r"#b1 #b0\)\)"
    ),
    # unsigned ×
    re.compile(
        r"\(concat \(\(_ extract (\d+) 0\) prod\) \(ite (\(bvuge prod \(_ bv\d+ \d+\)\)) #b1 #b0\)\)"
    ),
]


def repair_overflow_results(text: str) -> str:
    """Put the overflow flag of CBMC's `overflow_result` constructions above the result (see
    `OVERFLOW_RESULTS`), where CBMC's member accesses read it. Nothing else matches these
    patterns (`?sum` and `prod` are the names of CBMC's `let` in exactly these constructions)."""
    for pattern in OVERFLOW_RESULTS:
        var = "?sum" if "sum" in pattern.pattern else "prod"
        text = pattern.sub(
            lambda m: "(concat (ite %s #b1 #b0) ((_ extract %s 0) %s))" % (m.group(2), m.group(1), var),
            text,
        )
    return text


NESTED_ARRAY = re.compile(
    r"^\((?:declare-fun|define-fun) (\|[^|]*\||[^\s()]+) \(\) \(Array \(_ BitVec (\d+)\) "
    r"\(Array \(_ BitVec (\d+)\) \(_ (FloatingPoint (\d+) (\d+)|BitVec (\d+))\)\)\)",
    re.M,
)
BV_WIDTH = re.compile(
    r"^\((?:declare-fun|define-fun) (\|[^|]*\||[^\s()]+) \(\) \(_ BitVec (\d+)\)", re.M
)
ELEMENT_EQUATION = re.compile(
    r"^\(assert \(= \(let \(\(\?far (\|[^|]*\||[^\s()]+)\)\) \(select \?far (\(_ bv\d+ \d+\))\)\) "
    r"(\|[^|]*\||[^\s()]+)\)\)$",
    re.M,
)


def repair_array_elements(text: str) -> str:
    """Split an equation `(select A i) = S` between an element of a nested array (of floats or
    of bit-vectors, e.g. a `[Point3<f64>; 4]`) and a flattened bit-vector `S` of `k` elements (a
    by-value function argument) into `k` element equations `(select (select A i) j) = bits j of
    S` (`to_fp` of them for floats), element `j` in bits `[j·w, j·w + w)`: CBMC's flattening puts
    element 0 lowest, as for struct members. CBMC writes the mixed equation, which Bitwuzla
    rejects as ill-sorted. Elements `≥ k` of the inner array are left free (they are never read:
    Rust's bounds checks), an over-approximation, so `unsat` stays sound. Harnesses
    `z2_solver_nested_arrays` (true claims that depend on the element order) and
    `z3_nested_array_order_is_checked` (`should_panic`: a wrong order must be found) check the
    order in CI."""
    arrays = {}
    for m in NESTED_ARRAY.finditer(text):
        if m.group(5):
            arrays[m.group(1)] = (int(m.group(3)), int(m.group(5)), int(m.group(6)))
        else:
            arrays[m.group(1)] = (int(m.group(3)), 0, int(m.group(7)))
    if not arrays:
        return text
    widths = {m.group(1): int(m.group(2)) for m in BV_WIDTH.finditer(text)}

    def split(m):
        array, index, symbol = m.group(1), m.group(2), m.group(3)
        if array not in arrays or symbol not in widths:
            return m.group(0)
        index_width, e, sig = arrays[array]
        w = e + sig
        if widths[symbol] % w:
            return m.group(0)

        def bits(j):
            b = "((_ extract %d %d) %s)" % (j * w + w - 1, j * w, symbol)
            return "((_ to_fp %d %d) %s)" % (e, sig, b) if e else b

        parts = [
            "(= (select (select %s %s) (_ bv%d %d)) %s)" % (array, index, j, index_width, bits(j))
            for j in range(widths[symbol] // w)
        ]
        return "(assert (and %s))" % " ".join(parts)

    return ELEMENT_EQUATION.sub(split, text)


FLOAT_ARRAY = re.compile(
    r"^\(declare-fun (\|[^|]*\||[^\s()]+) \(\) \(Array \(_ BitVec \d+\) \(_ FloatingPoint (\d+) (\d+)\)\)\)$",
    re.M,
)
ELEMENT_SELECT = re.compile(r"\(select \?far (\(_ bv\d+ \d+\))\)")
FAR_LET = "(let ((?far "


def repair_float_array_concats(text: str) -> str:
    """Replace every `(let ((?far A)) (concat (select ?far k₁) … (select ?far kₙ)))` — the bits of
    a float array `A` passed by value (a `[f64; 4]`: CBMC flattens it so, as a function
    argument or as a member of a flattened struct) — by a fresh bit-vector `T` of the same width,
    with `A[kᵢ] = to_fp(bits of T)` for each element, the first element of the concat in the
    highest bits (SMT-LIB's `concat`). Bitwuzla rejects float arguments of `concat`. `T` is
    exactly the concat of the elements' bits, except that a NaN element may stand for any NaN
    bit pattern (as in `repair_float_sorts`), so `unsat` stays sound. Anything but a concat of
    selects of one float array is left as it is (Bitwuzla then rejects it: an error, never a
    wrong answer). Harnesses `z4_solver_float_array_arguments` (order-dependent true claims
    through such arrays are proved) and `z5_float_array_order_is_checked` (a claim that holds
    only for a permuted order is refuted) run in CI."""
    arrays = {m.group(1): (int(m.group(2)), int(m.group(3))) for m in FLOAT_ARRAY.finditer(text)}
    if not arrays or FAR_LET not in text:
        return text
    twins = {}  # (array, indices) -> twin name
    out = []
    last = 0
    i = text.find(FAR_LET)
    while i >= 0:
        # The let expression's extent (balanced parentheses; no strings or comments inside).
        depth, j = 0, i
        while True:
            c = text[j]
            if c == "(":
                depth += 1
            elif c == ")":
                depth -= 1
                if depth == 0:
                    break
            j += 1
        expr = text[i : j + 1]
        k = expr.index("))", len(FAR_LET))
        array = expr[len(FAR_LET) : k]
        body = expr[k + 2 : -1].strip()
        indices = ELEMENT_SELECT.findall(body)
        rest = ELEMENT_SELECT.sub("", body).replace("(concat", "").replace(")", "").strip()
        if array in arrays and indices and not rest:
            key = (array, tuple(indices))
            if key not in twins:
                twins[key] = "|%s__bits%d|" % (array.strip("|"), len(twins))
            out.append(text[last:i])
            out.append(twins[key])
            last = j + 1
        i = text.find(FAR_LET, j + 1)
    if not twins:
        return text
    out.append(text[last:])
    result = "".join(out)
    declarations = []
    links = []
    for (array, indices), twin in twins.items():
        e, sig = arrays[array]
        w = e + sig
        top = w * len(indices)
        declarations.append("(declare-fun %s () (_ BitVec %d))\n" % (twin, top))
        for n, index in enumerate(indices):
            hi = top - 1 - n * w
            links.append(
                "(assert (= (select %s %s) ((_ to_fp %d %d) ((_ extract %d %d) %s))))\n"
                % (array, index, e, sig, hi, hi - w + 1, twin)
            )
    first = min(p for p in (result.find("\n(declare-fun"), result.find("\n(define-fun")) if p >= 0)
    result = result[: first + 1] + "".join(declarations) + result[first + 1 :]
    check = result.find("(check-sat")
    if check < 0:
        return result + "".join(links)
    return result[:check] + "".join(links) + result[check:]


ZERO_WIDTH = re.compile(r"^\(declare-fun (\|[^|]*\||[^\s()]+) \(\) \(_ BitVec 0\)\)$", re.M)


def zero_width_unused(text: str) -> str:
    """Drop declarations of zero-width bit-vectors (zero-sized Rust values) that nothing uses:
    SMT-LIB has no `(_ BitVec 0)`. A used one is left for Bitwuzla to reject (an error, never a
    wrong answer)."""
    def keep(m):
        return m.group(0) if text.count(m.group(1)) > 1 else "; zero-width " + m.group(1)
    return ZERO_WIDTH.sub(keep, text)


def die_with_parent() -> None:
    """Exit when CBMC exits: Kani's per-harness timeout kills CBMC, not the solver it started,
    and an orphaned solver would keep a core busy for hours (it did, once)."""
    try:
        import ctypes
        import signal

        PR_SET_PDEATHSIG = 1
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() == 1:  # the parent is already gone
            sys.exit(1)
    except (OSError, AttributeError):
        pass  # not Linux: no orphan protection


def self_test() -> int:
    """Check `repair_float_array_concats` on a small input (exact output; `.ci/run` runs it, no
    solver needed): the element order, one twin per distinct expression, and a bit-vector array
    left alone."""
    text = (
        "(declare-fun array.1 () (Array (_ BitVec 64) (_ FloatingPoint 11 53)))\n"
        "(declare-fun array.2 () (Array (_ BitVec 64) (_ BitVec 8)))\n"
        "(declare-fun |s| () (_ BitVec 128))\n"
        "(assert (= (let ((?far array.1)) (concat (select ?far (_ bv1 64)) (select ?far (_ bv0 64)))) |s|))\n"
        "(assert (= (let ((?far array.1)) (concat (select ?far (_ bv1 64)) (select ?far (_ bv0 64)))) |s|))\n"
        "(assert (= (let ((?far array.2)) (concat (select ?far (_ bv1 64)) (select ?far (_ bv0 64)))) (_ bv0 16)))\n"
        "(check-sat)\n"
    )
    want = (
        "(declare-fun array.1 () (Array (_ BitVec 64) (_ FloatingPoint 11 53)))\n"
        "(declare-fun |array.1__bits0| () (_ BitVec 128))\n"
        "(declare-fun array.2 () (Array (_ BitVec 64) (_ BitVec 8)))\n"
        "(declare-fun |s| () (_ BitVec 128))\n"
        "(assert (= |array.1__bits0| |s|))\n"
        "(assert (= |array.1__bits0| |s|))\n"
        "(assert (= (let ((?far array.2)) (concat (select ?far (_ bv1 64)) (select ?far (_ bv0 64)))) (_ bv0 16)))\n"
        "(assert (= (select array.1 (_ bv1 64)) ((_ to_fp 11 53) ((_ extract 127 64) |array.1__bits0|))))\n"
        "(assert (= (select array.1 (_ bv0 64)) ((_ to_fp 11 53) ((_ extract 63 0) |array.1__bits0|))))\n"
        "(check-sat)\n"
    )
    got = repair_float_array_concats(text)
    if got != want:
        print("bitwuzla_cli.py self-test FAILED:\n--- got\n%s--- want\n%s" % (got, want), file=sys.stderr)
        return 1
    print("bitwuzla_cli.py: self-test passed")
    return 0


def main() -> int:
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    die_with_parent()
    import bitwuzla

    files = [a for a in sys.argv[1:] if not a.startswith("-")]
    if len(files) != 1:
        print("usage: bitwuzla FILE.smt2", file=sys.stderr)
        return 2
    with open(files[0]) as f:
        text = repair_float_sorts(
            repair_float_array_concats(repair_array_elements(repair_overflow_results(f.read())))
        )
    dump = os.environ.get("PACS_SMT_DUMP")
    if dump:
        with open(dump, "w") as f:
            f.write(text)
    terms = bitwuzla.TermManager()
    options = bitwuzla.Options()
    options.set(bitwuzla.Option.PRODUCE_MODELS, True)
    # Solver options for experiments: `PACS_BITWUZLA_OPTIONS="SAT_SOLVER=kissat REWRITE_LEVEL=2"`
    # (names of `bitwuzla.Option`; values as Bitwuzla's command line takes them).
    for item in os.environ.get("PACS_BITWUZLA_OPTIONS", "").split():
        name, _, value = item.partition("=")
        option = getattr(bitwuzla.Option, name.upper(), None)
        flag = {"1": True, "true": True, "on": True, "0": False, "false": False, "off": False}
        try:
            if option is None:
                raise ValueError("no Bitwuzla option %r" % name)
            if options.is_mode(option):
                options.set(option, value)
            elif options.is_bool(option):
                if value.lower() not in flag:
                    raise ValueError("%s takes true or false, not %r" % (name, value))
                options.set(option, flag[value.lower()])
            else:
                options.set(option, int(value))
        except (ValueError, bitwuzla.BitwuzlaException) as e:
            print("bitwuzla_cli.py: PACS_BITWUZLA_OPTIONS: %s" % e, file=sys.stderr)
            return 2
    parser = bitwuzla.Parser(terms, options)
    try:
        parser.parse(text, False, False)
    except bitwuzla.BitwuzlaException as e:
        keep = os.environ.get("PACS_SMT_KEEP_FAILED")
        if keep:
            with open(keep, "w") as f:
                f.write(text)
        # CBMC reports `(error "...")` answers with the message (as for the real binary).
        message = str(e).replace("\\", "/").replace('"', "'")
        print('(error "%s")' % message, flush=True)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
