"""demseis.evaluation.fieldio: masks and sections read back from .npy, .png and SEG-Y as they
were written, the PNG background rule, resampling, and each bad input as one InputError."""

from __future__ import annotations

import numpy as np
import pytest
import segyio
from PIL import Image

from demseis.errors import InputError
from demseis.evaluation.fieldio import (is_mask_file, read_mask, read_masks, read_section,
                                        resize_sections)


def _mask(h=20, w=30, seed=0):
    rng = np.random.default_rng(seed)
    m = np.zeros((h, w), bool)
    m[:, int(rng.integers(3, w - 3))] = True
    m[int(rng.integers(2, h - 2)), 2:12] = True
    return m


def _segy(path, section):
    """A SEG-Y file of the (samples, traces) ``section`` (a trace per column)."""
    segyio.tools.from_array2D(str(path), np.ascontiguousarray(section.T, np.float32), format=5)
    return path


@pytest.mark.parametrize("style", ["black_on_white", "white_on_black", "red_on_grey",
                                   "clear_background", "palette", "bilevel", "grey16"])
def test_png_masks_round_trip(tmp_path, style):
    m = _mask()
    if style == "black_on_white":
        img = Image.fromarray(np.where(m, 0, 255).astype(np.uint8))
    elif style == "white_on_black":
        img = Image.fromarray(np.where(m, 255, 0).astype(np.uint8))
    elif style == "red_on_grey":
        rgb = np.full((*m.shape, 3), 128, np.uint8)
        rgb[m] = (255, 0, 0)
        img = Image.fromarray(rgb)
    elif style == "clear_background":  # transparent pixels of any colour are background
        rgba = np.zeros((*m.shape, 4), np.uint8)
        rgba[..., :3] = np.random.default_rng(1).integers(0, 256, (*m.shape, 3))
        rgba[m] = (0, 0, 0, 255)
        img = Image.fromarray(rgba)
    elif style == "palette":
        img = Image.fromarray(np.where(m, 0, 255).astype(np.uint8)).convert("P")
    elif style == "bilevel":
        img = Image.fromarray(np.where(m, 0, 255).astype(np.uint8)).convert("1")
    else:
        img = Image.fromarray(np.where(m, 40000, 1000).astype(np.uint16))
    img.save(tmp_path / "m.png")
    got = read_mask(tmp_path / "m.png")
    assert got.dtype == bool and got.shape == m.shape
    np.testing.assert_array_equal(got, m)


def test_png_anti_aliased_edges_count_as_fault(tmp_path):
    """Any value other than the background is a fault, however faint."""
    grey = np.full((10, 10), 255, np.uint8)
    grey[:, 4] = 0
    grey[:, 5] = 254
    Image.fromarray(grey).save(tmp_path / "m.png")
    assert read_mask(tmp_path / "m.png").sum(axis=0).tolist() == [0] * 4 + [10, 10] + [0] * 4


def test_npy_and_segy_masks_round_trip(tmp_path):
    m = _mask()
    for name, arr in (("bool", m), ("u8", m.astype(np.uint8) * 255), ("f", m * 0.3),
                      ("stack1", m[None].astype(np.int16))):
        np.save(tmp_path / f"{name}.npy", arr)
        np.testing.assert_array_equal(read_mask(tmp_path / f"{name}.npy"), m)
    stack = np.stack([m, _mask(seed=2), np.zeros_like(m)])  # a section may have no fault
    np.save(tmp_path / "stack.npy", stack)
    np.testing.assert_array_equal(read_masks(tmp_path / "stack.npy"), stack)
    with pytest.raises(InputError, match="holds 3 masks"):
        read_mask(tmp_path / "stack.npy")
    for suffix in (".sgy", ".SEGY"):
        path = _segy(tmp_path / f"m{suffix}", m.astype(np.float32))
        np.testing.assert_array_equal(read_mask(path), m)
        assert read_masks(path).shape == (1, *m.shape)


def test_sections_round_trip(tmp_path):
    sec = np.random.default_rng(0).normal(size=(20, 30)).astype(np.float32)
    np.save(tmp_path / "s.npy", sec.astype(np.float64))
    np.save(tmp_path / "s1.npy", sec[None])
    np.testing.assert_array_equal(read_section(tmp_path / "s.npy"), sec)
    np.testing.assert_array_equal(read_section(tmp_path / "s1.npy"), sec)
    got = read_section(_segy(tmp_path / "s.sgy", sec))
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got, sec)
    grey = np.arange(600).reshape(20, 30) % 256
    Image.fromarray(grey.astype(np.uint8)).save(tmp_path / "s.png")
    np.testing.assert_allclose(read_section(tmp_path / "s.png"), grey / 255.0, atol=1e-7)
    rgb = np.stack([grey] * 3, axis=-1).astype(np.uint8)
    Image.fromarray(rgb).save(tmp_path / "rgb.png")
    np.testing.assert_allclose(read_section(tmp_path / "rgb.png"), grey / 255.0, atol=1e-7)


def test_bad_files_are_one_line_errors(tmp_path):
    np.save(tmp_path / "empty.npy", np.zeros((5, 5)))
    np.save(tmp_path / "nan.npy", np.full((5, 5), np.nan))
    np.save(tmp_path / "4d.npy", np.ones((1, 1, 5, 5)))
    np.save(tmp_path / "text.npy", np.array(["a", "b"]))
    (tmp_path / "junk.npy").write_bytes(b"not numpy")
    (tmp_path / "junk.png").write_bytes(b"not png")
    (tmp_path / "junk.sgy").write_bytes(b"not segy")
    Image.fromarray(np.full((5, 5), 255, np.uint8)).save(tmp_path / "blank.png")
    cases = [("none.png", "does not exist"), ("empty.npy", "no fault pixels"),
             ("blank.png", "no fault pixels"), ("nan.npy", "NaN"), ("4d.npy", r"\(1, 1, 5, 5\)"),
             ("text.npy", "numeric"), ("junk.npy", "cannot read as .npy"),
             ("junk.png", "cannot read as PNG"), ("junk.sgy", "cannot read as SEG-Y"),
             ("m.tif", r"\.npy, \.png")]
    for name, message in cases:
        with pytest.raises(InputError, match=message) as err:
            read_mask(tmp_path / name)
        assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="one section"):
        read_section(tmp_path / "4d.npy")
    with pytest.raises(InputError, match="NaN"):
        read_section(tmp_path / "nan.npy")


def test_is_mask_file(tmp_path):
    assert is_mask_file("a.png") and is_mask_file("b.SGY") and is_mask_file(tmp_path / "c.npy")
    assert not is_mask_file("store.zarr") and not is_mask_file(tmp_path)
    (tmp_path / "odd.npy").mkdir()  # a directory is a store, whatever its name
    assert not is_mask_file(tmp_path / "odd.npy")


def test_resize_sections_is_bilinear_with_aligned_centres():
    ramp = np.tile(np.arange(4, dtype=np.float32), (4, 1))[None]  # value = column
    up = resize_sections(ramp, (8, 8))[0]
    # output column j sits at source column (j + 0.5) / 2 - 0.5, clamped to [0, 3]
    want = np.clip((np.arange(8) + 0.5) / 2 - 0.5, 0, 3)
    np.testing.assert_allclose(up, np.tile(want, (8, 1)), atol=1e-6)
    p = np.random.default_rng(0).random((2, 7, 9)).astype(np.float32)
    down = resize_sections(p, (5, 4))
    assert down.shape == (2, 5, 4) and p.min() <= down.min() and down.max() <= p.max()
    np.testing.assert_array_equal(resize_sections(p, (7, 9)), p)  # same grid: unchanged
