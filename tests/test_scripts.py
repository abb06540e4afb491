"""The docs-figure scripts (outside the package) still run end to end (slow)."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


@pytest.mark.slow
def test_seismic_figures_render(tmp_path):
    spec = importlib.util.spec_from_file_location("seismic_figures", SCRIPTS / "seismic_figures.py")
    figures = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(figures)
    from demseis.types import Grid
    from demseis_dev.toys import faulted_sequence

    snaps = faulted_sequence(800.0, 500.0, n_layers=8, throw_m=100.0, n_snapshots=3,
                             rng=np.random.default_rng(0))
    grid = Grid.covering(800.0, 500.0)
    figures.frequency_sequence_figure(snaps, grid, tmp_path / "a.png", "toy")
    figures.properties_figure(snaps[-1], grid, tmp_path / "b.png", "toy")
    figures.tuning_figure(tmp_path / "c.png")
    assert all((tmp_path / n).stat().st_size > 10_000 for n in ("a.png", "b.png", "c.png"))


FIELD = Path(__file__).resolve().parents[2] / "shared" / "field" / "f3_inline.sgy"


@pytest.mark.slow
@pytest.mark.skipif(not FIELD.is_file(), reason="needs ../shared/field/f3_inline.sgy")
def test_field_figures_render(tmp_path):
    """scripts/survey_figure.py on two small survey-sampled stores and
    scripts/f3_prediction_figure.py on a made-up prediction: both draw F3 beside them."""
    import json
    import subprocess
    import sys

    from tests.generator._helpers import generate_tiny

    for rendering in ("elements", "strata"):
        toml = ('[sweep]\nn_runs = 1\nsnr_db = inf\n[model]\nengine = "kinematic"\n'
                f'[output]\ndomain = "time"\ndt_s = 0.004\ntrace_spacing_m = 25.0\n'
                f'rendering = "{rendering}"\n')
        generate_tiny(tmp_path, toml, f"kinematic_{rendering}")
    root = Path(__file__).resolve().parents[1]
    env = {"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"}
    subprocess.run([sys.executable, str(SCRIPTS / "survey_figure.py"), str(tmp_path),
                    "--freq", "30", "--out", str(tmp_path / "s.png")], check=True, env=env)
    prob = np.zeros((222, 440), np.float32)
    prob[:, 200] = 0.9                                   # one trace of 440: 0.23 %
    np.save(tmp_path / "p.npy", prob)
    out = subprocess.run([sys.executable, str(SCRIPTS / "f3_prediction_figure.py"),
                          str(tmp_path / "p.npy"), "--out", str(tmp_path / "p.png")],
                         check=True, env=env, capture_output=True, text=True).stdout
    assert json.loads(out)["share_above_0.5"][str(tmp_path / "p.npy")] == 0.0023
    assert (tmp_path / "s.png").stat().st_size > 20_000 and (tmp_path / "p.png").stat().st_size > 20_000


@pytest.mark.slow
@pytest.mark.skipif(not FIELD.is_file(), reason="needs ../shared/field/f3_inline.sgy")
def test_realism_figure_renders(tiny_store, tmp_path):
    """scripts/realism_figure.py: the tiny store beside F3, with the licence line."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    env = {"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, str(SCRIPTS / "realism_figure.py"), str(tiny_store),
                          "--max-samples", "4", "--out", str(tmp_path / "r.png")],
                         check=True, env=env, capture_output=True, text=True).stdout
    assert "| adjacent-trace correlation |" in out and "| 0.917 |" in out
    assert (tmp_path / "r.png").stat().st_size > 20_000


@pytest.mark.slow
def test_stretch_figure_renders(tmp_path):
    """scripts/stretch_figure.py draws a stretched section with its labelled faults (~10 s)."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, str(SCRIPTS / "stretch_figure.py"), "--stretch", "0.1",
                          "--out", str(tmp_path / "s.png")], check=True, capture_output=True,
                         text=True, env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
                         cwd=root).stdout
    assert int(out.split(": ")[1].split()[0]) >= 3
    assert (tmp_path / "s.png").stat().st_size > 20_000


@pytest.mark.slow
def test_survey_look_figure_renders(tmp_path):
    """scripts/survey_look_figure.py: one section under each wavelet, noise and processing."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, str(SCRIPTS / "survey_look_figure.py"),
                          "--out", str(tmp_path / "s.png")], check=True, capture_output=True,
                         text=True, env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
                         cwd=root).stdout
    assert out.count(": rms ") == 12
    assert (tmp_path / "s.png").stat().st_size > 50_000
