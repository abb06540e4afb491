"""The command line reads the same everywhere: every command's --help says what it does, the
store argument is STORE, errors name the flag the user typed, sizes are human, and asking for
more workers than cores is warned about."""

from __future__ import annotations

import argparse
import os

import pytest

from demseis.cli import build_parser, main
from demseis.generator.sweep.driver import human_bytes


def _commands(parser: argparse.ArgumentParser, prefix: str = ""):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield prefix + name, sub
                yield from _commands(sub, prefix + name + " ")


COMMANDS = dict(_commands(build_parser()))


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_has_a_description(name):
    assert COMMANDS[name].description, f"demseis {name} --help has no description"


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_the_store_argument_is_called_STORE(name):
    positional = [a for a in COMMANDS[name]._actions
                  if not a.option_strings and not isinstance(a, argparse._SubParsersAction)]
    for a in positional:
        if a.dest in ("store", "path", "truth_store"):
            assert a.metavar == "STORE", (name, a.dest, a.metavar)


@pytest.mark.parametrize("extra,shown", [(["--freq", "0"], "--freq 0.0 is not allowed"),
                                         (["--freq", "20", "--snr", "abc"], "--snr 'abc'")])
def test_render_errors_name_the_flag(tiny_store, tmp_path, capsys, extra, shown):
    assert main(["render", str(tiny_store), *extra, "--out", str(tmp_path / "r.zarr")]) == 2
    err = capsys.readouterr().err
    assert shown in err and "sweep." not in err
    assert not (tmp_path / "r.zarr").exists()


def test_psf_angle_error_names_the_flag(tiny_store, tmp_path, capsys):
    assert main(["render", str(tiny_store), "--freq", "20", "--imaging", "psf",
                 "--psf-max-angle", "100", "--out", str(tmp_path / "r.zarr")]) == 2
    assert "--psf-max-angle 100.0 is not allowed" in capsys.readouterr().err


@pytest.mark.parametrize("n,text", [(0, "0 bytes"), (1023, "1,023 bytes"), (2048, "2.0 KiB"),
                                    (72_383_880.6 * 2**20, "69.0 TiB")])
def test_human_bytes(n, text):
    assert human_bytes(n) == text


def test_more_workers_than_cores_is_warned(monkeypatch, tmp_path, capsys):
    import demseis.api

    seen = {}

    class Done(Exception):
        pass

    def fake_generate(cfg, **kw):
        seen.update(kw)
        raise Done

    monkeypatch.setattr("demseis.cli.commands.generate.generate", fake_generate)
    too_many = (os.cpu_count() or 1) + 1
    with pytest.raises(Done):
        main(["generate", "--preset", "tiny", "--out", str(tmp_path / "x.zarr"),
              "--workers", str(too_many)])
    err = capsys.readouterr().err
    assert f"demseis: warning: --workers {too_many} exceeds the" in err and "cores" in err
    assert seen["workers"] == too_many  # a warning, not a refusal
    assert demseis.api.workers_warning(os.cpu_count() or 1) is None


def test_api_warns_about_more_workers_than_cores(monkeypatch, tmp_path):
    import demseis.api

    class Started(Exception):
        pass

    def start():
        raise Started

    monkeypatch.setattr(demseis.api, "start_forkserver", start)
    with pytest.warns(demseis.api.WorkersWarning, match="exceeds the"), pytest.raises(Started):
        demseis.api.generate("tiny", out=tmp_path / "x.zarr", workers=(os.cpu_count() or 1) + 1)


def test_relabel_progress_says_relabel(tiny_store, tmp_path, capsys):
    from demseis.generator.sweep.rerender import relabel

    relabel(tiny_store, tmp_path / "l.zarr", labels={}, progress=True)
    err = capsys.readouterr().err
    assert "relabel:" in err and "render:" not in err
