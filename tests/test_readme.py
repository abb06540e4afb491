"""The README's code is code: its PyTorch snippet runs, its commands exist."""

from __future__ import annotations

import re
from pathlib import Path


from demseis.cli import build_parser

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README.read_text(), flags=re.S)


def test_pytorch_snippet_runs(tiny_store):
    (code,) = [b for b in _blocks("python") if "FaultSegDataset" in b]
    # the tiny store is 40 x 90 cells and has 2 runs: smaller crops, every run in one split
    code = code.replace('"quick.zarr"', repr(str(tiny_store))).replace("crop=(96, 96)", "crop=(32, 32)")
    code = code.replace('split="train", ', "")
    code = code.replace("    ...", "    seen.append((x.shape, y.shape, y.dtype))")
    scope: dict = {"seen": []}
    exec(compile(code, "README.md", "exec"), scope)
    assert scope["seen"], "the README loader yielded nothing"
    xs, ys, dt = scope["seen"][0]
    assert tuple(xs[1:]) == (1, 32, 32) and tuple(ys[1:]) == (32, 32)


def test_tour_commands_exist():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    commands = set(sub.choices)
    tour = next(b for b in _blocks("bash") if "Five" in b or "demseis info" in b)
    used = {line.split()[1] for line in tour.splitlines() if line.startswith("demseis ")}
    assert used <= commands, used - commands


def test_python_api_snippet_runs(tmp_path, monkeypatch, capsys):
    (code,) = [b for b in _blocks("python") if "demseis.generate(" in b]
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    out = capsys.readouterr().out
    assert "<demseis.Store 'tiny.zarr'" in out and "snr_db" in out
    assert scope["sample"]["seismic"].shape == scope["store"].layout.shape
    assert scope["result"].overall.n_samples == len(scope["store"])


def test_tour_lines_parse_when_pasted():
    """Every tour line is a real command line (no `a | b` shorthand that fails when pasted)."""
    import shlex

    parser = build_parser()
    tour = next(b for b in _blocks("bash") if "Five" in b or "demseis info" in b)
    for line in tour.splitlines():
        if not line.startswith("demseis "):
            continue
        args = shlex.split(line.split("  #")[0])[1:]
        try:
            parser.parse_args(args)
        except SystemExit as exc:
            raise AssertionError(f"README tour line does not parse: {line!r}") from exc
