"""The public API of harness/__init__.py: every exported name resolves to the object
its module defines, and importing the package loads none of the heavy dependencies."""
from __future__ import annotations

import importlib
import subprocess
import sys

import harness


def test_the_exports_are_listed_once():
    assert sorted(harness.__all__) == sorted(harness._EXPORTS)


def test_every_exported_name_is_its_modules_object():
    for name in harness.__all__:
        module = importlib.import_module(harness._EXPORTS[name])
        assert getattr(harness, name) is getattr(module, name), name


def test_an_unknown_name_is_an_attribute_error():
    try:
        harness.no_such_function  # noqa: B018
    except AttributeError as error:
        assert "no_such_function" in str(error)
    else:
        raise AssertionError("an unknown name resolved")


def test_import_is_cheap():
    code = ("import sys, harness; heavy = [m for m in ('dask', 'distributed', 'matplotlib', "
            "'sympy', 'scipy', 'fmpy') if m in sys.modules]; print(','.join(heavy))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == ""



def test_the_command_line_parser_loads_no_model_machinery():
    """--help and every command's parsing: sympy, pint and scipy load with the commands
    that use them (the model package's names are loaded on first use)."""
    code = ("import sys; from harness.cli import build_parser; build_parser(); "
            "import harness.model; heavy = [m for m in ('sympy', 'pint', 'scipy', "
            "'matplotlib') if m in sys.modules]; print(','.join(heavy))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == ""
    assert harness.model.read_model.__module__ == "harness.model.reader"


def test_the_robot_path_loads_no_symbolic_machinery():
    """identify --robot's modules share the least squares and the cross-validation's rule
    with the model files' path, not its sympy and pint (about 1 s of a 3.4 s command)."""
    code = ("import sys; import harness.robot.cli, harness.robot.pipeline, "
            "harness.robot.validate; heavy = [m for m in ('sympy', 'pint') "
            "if m in sys.modules]; print(','.join(heavy))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == ""
