"""FaultSegDataset and ShardAwareSampler: splits, filters, crops, pickling, workers."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest
import torch
from torch.utils.data import DataLoader

from demseis.datasets import FaultSegDataset, ShardAwareSampler, open_store, split_of_shards
from demseis.datasets.dataset import crop_offsets
from demseis.errors import InputError
from tests.datasets._helpers import make_store, zarr_params

SHAPE = (24, 32)
S = 6


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    # 20 runs, shard 7 pending (e.g. its DEM run failed)
    path = tmp_path_factory.mktemp("ds") / "s.zarr"
    return make_store(path, n_shards=20, s=S, shape=SHAPE,
                      write=[k for k in range(20) if k != 7])


def test_splits_never_share_a_run_and_cover_every_done_run(store):
    parts = {sp: FaultSegDataset(store, split=sp) for sp in ("train", "val", "test")}
    runs = {sp: set(ds.run_ids.tolist()) for sp, ds in parts.items()}
    assert runs["train"].isdisjoint(runs["val"])
    assert runs["train"].isdisjoint(runs["test"])
    assert runs["val"].isdisjoint(runs["test"])
    # runs stored in params agree with the shard each item comes from
    for ds in parts.values():
        np.testing.assert_array_equal(ds.run_ids, ds.shard_of_item)
        for i in range(len(ds)):
            assert ds.params(i)["run_id"] == ds.run_ids[i]
    everything = FaultSegDataset(store)
    assert sum(len(ds) for ds in parts.values()) == len(everything) == 19 * S
    assert runs["train"] | runs["val"] | runs["test"] == set(range(20)) - {7}
    # fixed seed: same split every time; another seed: another split
    assert set(FaultSegDataset(store, split="test").run_ids.tolist()) == runs["test"]
    other = FaultSegDataset(store, split="test", split_seed=1)
    assert set(other.run_ids.tolist()) != runs["test"]


def test_split_of_shards_fractions_and_stability():
    labels = split_of_shards(100, (0.7, 0.2, 0.1), seed=3)
    assert np.bincount(labels, minlength=3).tolist() == [70, 20, 10]
    np.testing.assert_array_equal(labels, split_of_shards(100, (0.7, 0.2, 0.1), seed=3))
    assert np.bincount(split_of_shards(3), minlength=3).tolist() == [1, 1, 1]
    assert np.bincount(split_of_shards(5, (1.0, 0.0, 0.0)), minlength=3).tolist() == [5, 0, 0]
    with pytest.raises(InputError, match="split_fractions"):
        split_of_shards(10, (0.5, 0.2, 0.2))


def test_where_filters(store):
    g = open_store(store)
    stored = zarr_params(store)
    freq, snr = stored["freq_hz"], stored["snr_db"]
    done = np.repeat(g["shard_done"][:] == 1, S)

    def expect(mask):
        return np.nonzero(mask & done)[0]

    np.testing.assert_array_equal(FaultSegDataset(store, where={"freq_hz": 40}).indices,
                                  expect(np.isclose(freq, 40)))
    np.testing.assert_array_equal(FaultSegDataset(store, where={"freq_hz": (30, None)}).indices,
                                  expect(freq >= 30))
    np.testing.assert_array_equal(
        FaultSegDataset(store, where={"freq_hz": [20, 60], "snr_db": np.inf}).indices,
        expect(np.isin(freq, [20, 60]) & np.isinf(snr)))
    np.testing.assert_array_equal(
        FaultSegDataset(store, where=lambda p: (p["snapshot"] == 2) & (p["run_id"] < 5)).indices,
        expect((stored["snapshot"] == 2) & (stored["run_id"] < 5)))
    with pytest.raises(InputError, match="unknown parameter 'dip'"):
        FaultSegDataset(store, where={"dip": 3})
    with pytest.raises(InputError, match="bool array"):
        FaultSegDataset(store, where=lambda p: p["run_id"])


def test_items_match_the_store_at_the_crop_window(store):
    g = open_store(store)
    ds = FaultSegDataset(store, ("seismic", "strain"), ("fault", "layer"), crop=(10, 13), seed=5)
    for i in (0, 7, len(ds) - 1):
        x, y = ds[i]
        assert x.dtype == torch.float32 and x.shape == (2, 10, 13)
        assert y["fault"].dtype == torch.uint8 and y["layer"].dtype == torch.int16
        # find the window: it must be the same for every array of the sample
        gi = int(ds.indices[i])
        full = g["seismic"][gi]
        hits = [(r, c) for r in range(SHAPE[0] - 9) for c in range(SHAPE[1] - 12)
                if np.array_equal(full[r:r + 10, c:c + 13], x[0].numpy())]
        assert len(hits) == 1
        r, c = hits[0]
        np.testing.assert_array_equal(x[1].numpy(), g["strain"][gi, r:r + 10, c:c + 13])
        np.testing.assert_array_equal(y["fault"].numpy(), g["fault"][gi, r:r + 10, c:c + 13])
        np.testing.assert_array_equal(y["layer"].numpy(), g["layer"][gi, r:r + 10, c:c + 13])
    # crops are random across samples and epochs, fixed for a given (seed, epoch, sample)
    a = [ds[i][0] for i in range(10)]
    ds.set_epoch(1)
    b = [ds[i][0] for i in range(10)]
    ds.set_epoch(0)
    assert all(torch.equal(u, ds[i][0]) for i, u in enumerate(a))
    assert not all(torch.equal(u, v) for u, v in zip(a, b))


def test_full_samples_long_labels_and_transform(store):
    g = open_store(store)
    ds = FaultSegDataset(store, ("seismic",), ("damage",), long_labels=True,
                         transform=lambda x, y: (x * 2, y + 1))
    x, y = ds[3]
    gi = int(ds.indices[3])
    assert x.shape == (1, *SHAPE) and y.shape == SHAPE and y.dtype == torch.int64
    np.testing.assert_array_equal(x[0].numpy(), 2 * g["seismic"][gi])
    np.testing.assert_array_equal(y.numpy(), g["damage"][gi].astype(np.int64) + 1)


def test_getitems_equals_getitem(store):
    ds = FaultSegDataset(store, ("seismic",), ("fault",), crop=16)
    idx = [5, 40, 41, 6, 100, 5]
    batch = ds.__getitems__(idx)
    for i, (x, y) in zip(idx, batch):
        x1, y1 = ds[i]
        assert torch.equal(x, x1) and torch.equal(y, y1)


def test_pickles_without_open_store(store):
    ds = FaultSegDataset(store, crop=16)
    ds[0]  # opens the store in this process
    blob = pickle.dumps(ds)
    assert b"zarr.core" not in blob and b"memmap" not in blob and len(blob) < 20_000
    clone = pickle.loads(blob)
    assert clone._arrays is None
    assert torch.equal(clone[3][0], ds[3][0])


def test_shard_aware_sampler_order(store):
    ds = FaultSegDataset(store, split="train")
    sampler = ShardAwareSampler(ds, shards_per_block=2, seed=1)
    order = sampler.order()
    assert sorted(order.tolist()) == list(range(len(ds)))
    shards = ds.shard_of_item[order]
    # consecutive blocks of 2 shards: each shard's items are all within one block
    block_of = {}
    for pos, sh in enumerate(shards.tolist()):
        block_of.setdefault(sh, set()).add(pos // (2 * S))
    assert all(len(b) == 1 for b in block_of.values())
    np.testing.assert_array_equal(order, ShardAwareSampler(ds, shards_per_block=2, seed=1).order())
    sampler.set_epoch(1)
    assert not np.array_equal(order, sampler.order())
    assert list(ShardAwareSampler(ds, shuffle=False)) == list(range(len(ds)))


def test_dataloader_two_workers_same_batches_as_in_process(store):
    ds = FaultSegDataset(store, ("seismic",), ("fault",), crop=16, split="train")
    kw = dict(batch_size=8, sampler=ShardAwareSampler(ds, seed=2))
    ref = list(DataLoader(ds, num_workers=0, **kw))
    got = list(DataLoader(ds, num_workers=2, **kw))
    assert len(ref) == len(got) == -(-len(ds) // 8)
    for (x0, y0), (x1, y1) in zip(ref, got):
        assert x0.shape[1:] == (1, 16, 16)
        assert torch.equal(x0, x1) and torch.equal(y0, y1)
    assert sum(x.shape[0] for x, _ in got) == len(ds)


def test_dataset_argument_errors(store, tmp_path):
    with pytest.raises(InputError, match="'impedance' is not in store"):
        FaultSegDataset(store, ("impedance",))
    with pytest.raises(InputError, match="crop"):
        FaultSegDataset(store, crop=(30, 10))
    with pytest.raises(InputError, match="split"):
        FaultSegDataset(store, split="training")
    with pytest.raises(IndexError):
        FaultSegDataset(store)[10_000]


def test_import_is_light():
    code = ("import sys, demseis.datasets; "
            "print(any(m in sys.modules for m in ('torch', 'dask', 'matplotlib')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_crop_offsets_cover_the_range_uniformly():
    samples = np.arange(200_000)
    r, c = crop_offsets(3, 0, samples, 22, 245)
    assert r.min() == 0 and r.max() == 21 and c.min() == 0 and c.max() == 244
    # chi-square against uniform (22 bins): far below the 0.1 % critical value (~46.8, 21 dof)
    counts = np.bincount(r, minlength=22)
    chi2 = ((counts - len(samples) / 22) ** 2 / (len(samples) / 22)).sum()
    assert chi2 < 46.8
    assert abs(np.corrcoef(r, c)[0, 1]) < 0.01  # rows and columns independent
    r2, _ = crop_offsets(3, 1, samples, 22, 245)
    assert (r2 == r).mean() < 0.1  # a new epoch gives new windows
    np.testing.assert_array_equal(crop_offsets(3, 0, samples[::7], 22, 245)[0], r[::7])
