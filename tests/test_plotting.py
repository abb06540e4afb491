"""demseis.plotting: the titles of the figures."""

from __future__ import annotations


def test_a_noise_free_sample_is_titled_no_noise():
    """issue 38: the plot of a noise-free sample was titled "SNR inf dB (band)"."""
    from demseis.plotting import noise_title

    assert noise_title(float("inf"), "band") == "no noise"
    assert noise_title("inf", "white") == "no noise"
    assert noise_title(10.0, "white") == "SNR 10 dB (white)"


def test_otsu_threshold_matches_scikit_image():
    """The display threshold is Otsu's: the same split of a bimodal prediction as
    ``skimage.filters.threshold_otsu`` (whose bins span the data's range, not [0, 1], so the
    two agree within a bin of either)."""
    import numpy as np
    from skimage.filters import threshold_otsu

    from demseis.plotting import otsu_threshold

    rng = np.random.default_rng(0)
    for lo, hi, frac in [(0.05, 0.6, 0.03), (0.1, 0.9, 0.2), (0.02, 0.3, 0.01)]:
        v = np.concatenate([rng.normal(lo, 0.03, int(1e5 * (1 - frac))),
                            rng.normal(hi, 0.05, int(1e5 * frac))]).clip(0, 1)
        ours, theirs = otsu_threshold(v), float(threshold_otsu(v, nbins=256))
        assert abs(ours - theirs) <= 1 / 256 + (v.max() - v.min()) / 256, (ours, theirs)
        assert lo < ours < hi
    assert otsu_threshold(np.full(10, 0.3)) == 0.5


def test_plot_of_a_section_with_prediction_and_picks(tmp_path, capsys):
    """issue 38: `demseis plot SECTION --pred P --labels M` draws a section file with its
    prediction and picks (the command tells a section from a store by what it is given)."""
    import numpy as np
    from PIL import Image

    from demseis.cli import main

    rng = np.random.default_rng(1)
    sec = rng.normal(size=(60, 80)).astype(np.float32)
    prob = np.full((60, 80), 0.05, np.float32)
    prob[:, 40] = 0.4                                   # a low-probability fault still shows
    mask = np.zeros((60, 80), bool)
    mask[:, 41] = True
    for name, arr in (("s.npy", sec), ("p.npy", prob), ("m.npy", mask)):
        np.save(tmp_path / name, arr)
    out = tmp_path / "fig.png"
    assert main(["plot", str(tmp_path / "s.npy"), "--pred", str(tmp_path / "p.npy"),
                 "--labels", str(tmp_path / "m.npy"), "--out", str(out)]) == 0
    with Image.open(out) as im:
        assert im.size[0] > 2.5 * im.size[1]            # three panels side by side
    capsys.readouterr()
    np.save(tmp_path / "bad.npy", prob[:, :50])
    assert main(["plot", str(tmp_path / "s.npy"), "--pred", str(tmp_path / "bad.npy"),
                 "--out", str(out)]) == 2
    assert "has shape (60, 50), the section (60, 80)" in capsys.readouterr().err
    assert main(["plot", str(tmp_path / "s.npy"), "--sample", "3", "--out", str(out)]) == 2
    assert "--sample is for a store" in capsys.readouterr().err


def test_plot_a_line_of_a_3d_cube_with_its_prediction(tmp_path, capsys):
    """issue 38: `demseis plot CUBE.sgy --pred P.sgy --inline N` draws one line of a cube
    (picked by its header number) with the same line of the prediction cube."""
    import numpy as np

    from demseis.cli import main
    from demseis.evaluation.segyfile import read_cube_line, write_segy_cube_like
    from tests.evaluation._helpers import write_cube

    rng = np.random.default_rng(0)
    cube = rng.normal(size=(4, 6, 32)).astype(np.float32)
    write_cube(tmp_path / "c.sgy", cube, [1, 2, 3, 4], [20, 21, 22, 23, 24, 25])
    prob = rng.random((4, 6, 32)).astype(np.float32)
    write_segy_cube_like(prob, tmp_path / "c.sgy", tmp_path / "p.sgy")
    np.testing.assert_allclose(read_cube_line(tmp_path / "p.sgy", "crossline", 22), prob[:, 2].T)
    np.testing.assert_allclose(read_cube_line(tmp_path / "c.sgy", "inline", 3), cube[2].T,
                               rtol=1e-6)                          # IBM floats read back
    out = tmp_path / "l.png"
    assert main(["plot", str(tmp_path / "c.sgy"), "--pred", str(tmp_path / "p.sgy"),
                 "--inline", "3", "--out", str(out)]) == 0
    assert out.stat().st_size > 5_000
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "c.sgy"), "--out", str(out)]) == 2
    assert "is a 3-D cube: give --inline N or --crossline N" in capsys.readouterr().err
    assert main(["plot", str(tmp_path / "c.sgy"), "--crossline", "99", "--out", str(out)]) == 2
    assert "has no crossline 99: its crosslines are 20..25" in capsys.readouterr().err
