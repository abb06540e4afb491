"""demseis.registry: entries by name, lazily imported paths, installed entry points, and the
``"module:attribute"`` names and ``plugins`` modules that let a plug-in reach every process."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from demseis.errors import InputError
from demseis.registry import Registry, load_plugins
from tests._helpers import ROOT


def test_names_keep_registration_order_and_paths_load_lazily():
    reg = Registry("thing", {"a": "json:dumps"})
    reg.register("b", len)
    assert reg.names() == ("a", "b") and len(reg) == 2 and "a" in reg
    assert reg.get("a") is json.dumps and reg.index("b") == 1
    with pytest.raises(InputError, match="already registered"):
        reg.register("a", len)
    with pytest.raises(InputError, match=r"unknown thing 'c': expected one of 'a', 'b'"):
        reg.get("c")


def test_a_module_attribute_name_is_imported_and_registered():
    reg = Registry("thing")
    assert "os.path:join" in reg
    assert reg.get("os.path:join") is os.path.join and reg.names() == ("os.path:join",)
    assert reg.get("json:JSONDecoder.decode") is json.JSONDecoder.decode   # a dotted attribute
    with pytest.raises(InputError, match="cannot import 'nonesuch_mod'"):
        reg.get("nonesuch_mod:x")
    with pytest.raises(InputError, match="has no 'nope'"):
        "os:nope" in reg  # noqa: B015 - the look-up itself raises
    assert "not a path" not in reg
    closed = Registry("array", paths=False)
    assert "os.path:join" not in closed
    with pytest.raises(InputError, match="unknown array"):
        closed.get("os.path:join")


def test_load_plugins_imports_modules_and_names_the_bad_one():
    load_plugins(["json", "os.path:join"])
    with pytest.raises(InputError, match="cannot import 'nonesuch_mod'"):
        load_plugins(["json", "nonesuch_mod"])
    with pytest.raises(InputError, match="not a module name"):
        load_plugins(["two words"])


def test_installed_entry_points_join_after_the_builtins(tmp_path):
    """A distribution that declares ``demseis.engines`` and ``demseis.arrays`` entry points
    (a dist-info folder on the path, as pip installs one): its engine is a valid config value
    and its array is declared, in a fresh process, without any import by the user."""
    dist = tmp_path / "demseis_toy-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: demseis-toy\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(
        "[demseis.engines]\nflat = tests.generator._flat:FLAT\n"
        "[demseis.arrays]\nlayer_parity = tests.generator._flat:PARITY\n")
    code = ("from demseis.registry import ENGINES\n"
            "from demseis.schema import SAMPLE_ARRAYS\n"
            "from demseis.generator.config.settings import load_config, parse_config\n"
            "raw = load_config(preset='tiny').to_dict(); raw['model']['engine'] = 'flat'\n"
            "print(ENGINES.names()); print(SAMPLE_ARRAYS.names()[-1])\n"
            "print(type(ENGINES.get('flat')).__name__, SAMPLE_ARRAYS.get('layer_parity').name)\n"
            "print(parse_config(raw).model.engine)\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True,
                         capture_output=True, text=True).stdout.splitlines()
    assert out[0] == str(("dem", "kinematic", "planar", "flat"))
    assert out[1] == "layer_parity"
    assert out[2] == "FlatEngine layer_parity"
    assert out[3] == "flat"
