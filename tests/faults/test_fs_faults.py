"""Filesystem faults: exit 2 and one line naming the path and the cause; a partial shard is never
marked done; a disk-full store resumes, once space is freed, to the bytes of an uninterrupted run."""

from __future__ import annotations

import errno
import shutil
import subprocess
import uuid
from pathlib import Path

import pytest

from demseis.cli import main
from tests.generator._helpers import assert_same_bytes


def _gen(out: Path, *extra: str) -> list[str]:
    return ["generate", "--preset", "tiny", "--out", str(out), "--workers", "0", "--quiet", *extra]


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fsref") / "ref.zarr"
    assert main(_gen(out)) == 0
    return out


def _one_error_line(err: str, *words: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("demseis: error: "), err
    for w in words:
        assert w in lines[0], lines[0]


def test_path_under_proc(capsys):
    assert main(_gen(Path("/proc/demseis-test.zarr"))) == 2
    _one_error_line(capsys.readouterr().err, "/proc/demseis-test.zarr")


def test_injected_disk_full_then_resume(reference, tmp_path, monkeypatch, capsys):
    """ENOSPC injected into the third array write of a shard (works on any machine)."""
    import demseis.datasets.write as store
    from demseis.datasets import shard_status

    real = store._write_array
    calls = []

    def full(root, arr, sel, data):
        calls.append(arr.path)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(root, arr, sel, data)

    monkeypatch.setattr(store, "_write_array", full)
    out = tmp_path / "full.zarr"
    assert main(_gen(out)) == 2
    _one_error_line(capsys.readouterr().err, str(out), "No space left on device", "resume")
    assert list(shard_status(out)) == [0, 0, 0]  # the partial shard is not marked done
    monkeypatch.setattr(store, "_write_array", real)
    assert main(_gen(out)) == 0
    assert_same_bytes(reference, out)


@pytest.fixture
def mount_point(tmp_path):
    """A fresh tmpfs mount point, or skip where the machine does not allow ``mount``."""
    mnt = tmp_path / f"mnt-{uuid.uuid4().hex[:6]}"
    mnt.mkdir()
    mounted = []

    def do_mount(options: str) -> Path:
        res = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(mnt)],
                             capture_output=True, text=True)
        if res.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs here: {res.stderr.strip()}")
        mounted.append(mnt)
        return mnt

    yield do_mount
    for m in mounted:
        subprocess.run(["umount", str(m)], capture_output=True)


def test_read_only_filesystem(mount_point, capsys):
    mnt = mount_point("ro,size=1m")
    assert main(_gen(mnt / "x.zarr")) == 2
    _one_error_line(capsys.readouterr().err, str(mnt / "x.zarr"), "Read-only file system")


def test_real_disk_full_then_resume(reference, mount_point, capsys):
    """A 3 MiB tmpfs, half taken by a filler file: the sweep runs out of space, exits 2 with one
    line, and after the filler is removed the same command completes the same bytes."""
    from demseis.datasets import shard_status

    mnt = mount_point("size=3m")
    filler = mnt / "filler"
    size = shutil.disk_usage(mnt).free - 300_000  # leaves less than the tiny store needs
    filler.write_bytes(b"\0" * size)
    out = mnt / "x.zarr"
    assert main(_gen(out)) == 2
    _one_error_line(capsys.readouterr().err, "No space left on device")
    if (out / "shard_done").exists():
        assert not all(s == 1 for s in shard_status(out))
    filler.unlink()
    assert main(_gen(out)) == 0
    assert_same_bytes(reference, out)


def test_plot_out_name_is_kept(reference, tmp_path, capsys):
    """``plot --out x`` writes x (PNG), not x.png; an unknown suffix is refused clearly."""
    out = tmp_path / "x"
    assert main(["plot", str(reference), "--sample", "1", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (tmp_path / "x.png").exists()
    capsys.readouterr()
    assert main(["plot", str(reference), "--sample", "1", "--out", str(tmp_path / "y.pngx")]) == 2
    _one_error_line(capsys.readouterr().err, "y.pngx", "unknown image type")


def test_object_predictions_are_named_not_a_pickle_hint(reference, tmp_path, capsys):
    import numpy as np

    pred = tmp_path / "p.npy"
    np.save(pred, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    assert main(["score", str(pred), str(reference)]) == 2
    _one_error_line(capsys.readouterr().err, "Python objects", "astype(np.float32)")
