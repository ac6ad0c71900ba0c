"""The package's documentation runs: the module docstring's example, the stubs name every
public attribute, the example scripts run."""

import doctest
import pathlib
import subprocess
import sys

import pacs
import pacs._pacs as native

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_module_docstring_example():
    failures, tried = doctest.testmod(pacs, verbose=False)
    assert tried >= 8 and failures == 0


def stub_classes():
    """Class name -> its block of the stub file."""
    stub = (ROOT / "python" / "pacs" / "_pacs.pyi").read_text()
    blocks, name = {}, None
    for line in stub.splitlines():
        if line.startswith("class "):
            name = line[6:].split("(")[0].split(":")[0]
            blocks[name] = ""
        elif line and not line.startswith(" "):
            name = None
        if name is not None:
            blocks[name] += line + "\n"
    return stub, blocks


def test_stubs_cover_the_extension():
    stub, blocks = stub_classes()
    for name in dir(native):
        if name.startswith("_") or name == "pacs":
            continue
        obj = getattr(native, name)
        if isinstance(obj, type):
            assert name in blocks, f"class {name} missing from _pacs.pyi"
            for attr in dir(obj):
                if not attr.startswith("_"):
                    assert f"def {attr}(" in blocks[name], f"{name}.{attr} missing from its stub"
        else:
            assert f"def {name}(" in stub, name


def test_stub_signatures_match():
    import inspect
    _, blocks = stub_classes()
    for cls in (native.Shield, native.ShieldLoop, native.LogWriter):
        for attr in ("set_chunk", "measure", "measure_object", "robot", "human", "object"):
            fn = getattr(cls, attr, None)
            if fn is None or not callable(fn):
                continue
            params = list(inspect.signature(fn).parameters)[1:]
            block = blocks[cls.__name__]
            line = block[block.index(f"def {attr}("):]
            line = line[: line.index(")")]
            names = [p.split(":")[0].strip() for p in line.split("(", 1)[1].split(",")]
            names = [n for n in names if n and n != "self"]
            assert names == params, f"{cls.__name__}.{attr}: stub {names}, module {params}"


def test_docstrings_have_units():
    for cls in (native.Shield, native.ShieldLoop, native.LogWriter):
        assert cls.__doc__ and len(cls.__doc__) > 200
    assert "(rad" in native.Shield.start.__doc__
    assert "`t` (s" in native.Shield.step.__doc__


def test_policy_loop_example_runs(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "policy_loop.py"), "--duration", "2",
         "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert '"audit_verdict": "pass"' in out.stdout
    assert (tmp_path / "report" / "report.html").exists()
