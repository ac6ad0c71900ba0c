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


def test_stubs_cover_the_extension():
    stub = (ROOT / "python" / "pacs" / "_pacs.pyi").read_text()
    for name in dir(native):
        if name.startswith("_") or name == "pacs":
            continue
        assert f"class {name}" in stub or f"def {name}(" in stub, name
        obj = getattr(native, name)
        if isinstance(obj, type):
            for attr in dir(obj):
                if not attr.startswith("_"):
                    assert f"def {attr}(" in stub, f"{name}.{attr} missing from _pacs.pyi"


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
