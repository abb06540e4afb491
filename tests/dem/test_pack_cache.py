"""The settled-pack cache of :func:`demseis.dem.settle_pack`: the same bytes from a warm or a
fresh cache, checksummed files (a damaged one is settled again with a warning), atomic writes
and a cache that cannot be written."""

from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest

from demseis.dem import Material, PackCacheWarning, settle_pack
from demseis.dem.assembly import _write_cached

BOX = dict(width_m=240.0, height_m=100.0, radius_min_m=6.0, radius_max_m=12.0)


def _settle(cache_dir, seed=3, **kw):
    return settle_pack(BOX["width_m"], BOX["height_m"], radius_min_m=BOX["radius_min_m"],
                       radius_max_m=BOX["radius_max_m"], rng=seed, cache_dir=cache_dir, **kw)


def _same(a, b):
    return a.xy.tobytes() == b.xy.tobytes() and a.radius.tobytes() == b.radius.tobytes()


def test_the_cache_gives_the_settled_bytes_warm_and_fresh(tmp_path):
    plain = _settle(None)
    first = _settle(tmp_path / "a")
    files = list((tmp_path / "a").iterdir())
    assert len(files) == 1 and files[0].name.startswith("pack_") and files[0].suffix == ".npz"
    with warnings.catch_warnings():
        warnings.simplefilter("error")       # a good file loads without a warning
        warm = _settle(tmp_path / "a")
    fresh = _settle(tmp_path / "b")
    assert _same(plain, first) and _same(first, warm) and _same(first, fresh)
    # another seed or material is another file
    _settle(tmp_path / "a", seed=4)
    _settle(tmp_path / "a", material=Material(friction=0.3))
    assert len(list((tmp_path / "a").glob("pack_*.npz"))) == 3


@pytest.mark.parametrize("damage", ["truncate", "flip", "other_arrays", "other_inputs"])
def test_a_damaged_file_is_detected_and_settled_again(tmp_path, damage):
    good = _settle(tmp_path)
    path = next(tmp_path.glob("pack_*.npz"))
    if damage == "truncate":
        path.write_bytes(path.read_bytes()[:200])
    elif damage == "flip":
        data = bytearray(path.read_bytes())
        data[len(data) // 3] ^= 0xFF
        path.write_bytes(bytes(data))
    else:
        with np.load(path) as z:
            entries = {k: z[k] for k in z.files}
        if damage == "other_arrays":   # moved disks under the old checksum
            entries["xy"] = entries["xy"] + 1.0
        else:                          # a file renamed from another pack's
            entries["key"] = np.array(str(entries["key"]).replace('"seed": 3', '"seed": 5'))
        with open(path, "wb") as f:
            np.savez(f, **entries)
    with pytest.warns(PackCacheWarning, match="damaged"):
        again = _settle(tmp_path)
    assert _same(good, again)
    with warnings.catch_warnings():
        warnings.simplefilter("error")       # rebuilt: the next load is clean
        assert _same(good, _settle(tmp_path))


def test_concurrent_writers_leave_one_whole_file(tmp_path):
    """Workers that settle the same pack at once each write a temporary file and rename it:
    one complete file stays, no temporary file."""
    pack = _settle(None)
    key = '{"test": 1}'
    path = tmp_path / "pack_x.npz"
    threads = [threading.Thread(target=_write_cached, args=(path, key, pack)) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert [p.name for p in tmp_path.iterdir()] == ["pack_x.npz"]
    with np.load(path) as z:
        assert z["xy"].tobytes() == pack.xy.tobytes() and str(z["key"]) == key


def test_a_cache_that_cannot_be_written_warns_and_still_settles(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.warns(PackCacheWarning, match="cannot be written"):
        pack = _settle(blocker / "packs")
    assert _same(pack, _settle(None))
