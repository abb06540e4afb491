"""benchmarks/field_benchmark.py end to end on tiny stores on the CPU, with a made-up "field" set
(display PNG + hand-drawn-like mask PNG written here from a synthetic section: no field data);
its readers, thinning and scoring helper."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("torch")

from demseis.errors import InputError  # noqa: E402

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "field_benchmark.py"
COMMON = BENCH.with_name("_field_common.py")


@pytest.fixture(scope="module")
def bench():
    return runpy.run_path(str(BENCH), run_name="field_benchmark")


@pytest.fixture(scope="module")
def common():
    """The readers, thinning and scoring helper the benchmark uses."""
    return runpy.run_path(str(COMMON), run_name="_field_common")


def _png(path: Path, arr: np.ndarray, mode: str) -> None:
    from PIL import Image

    Image.fromarray(arr, mode).save(path)


def _field_maps(common, root: Path, model) -> tuple[list, list]:
    """The model's probabilities on the fixture's field set, and its thinned masks, as the
    benchmark reads them."""
    from demseis.learning.model import predict_array

    maps, masks = [], []
    for sec_path in sorted((root / "set").glob("seismic_*")):
        mask_path = next((root / "set").glob(f"mask_{sec_path.stem[len('seismic_'):]}.*"))
        sec, mask = common["read_pair"](sec_path, mask_path, thin_lines=True)
        maps.append(predict_array(model, sec))
        masks.append(mask)
    return maps, masks


@pytest.fixture(scope="module")
def field(tmp_path_factory, tiny_store):
    """A field set in the tutorial-03 layout: seismic_<key>.png drawn 1.5 times the size of its
    mask_<key>.png (black lines 3 px wide on a transparent background); and the truth."""
    from scipy import ndimage

    import demseis
    from demseis.seismic.segy import write_segy

    root = tmp_path_factory.mktemp("field")
    d = root / "set"
    d.mkdir()
    s = demseis.open(tiny_store)
    keys = [i for i in range(len(s)) if s.sample(i)["fault"].any()][:2]
    truth = {}
    for k in keys:
        smp = s.sample(k)
        sec, mask = smp["seismic"], smp["fault"] > 0
        h, w = sec.shape
        big = ndimage.zoom(sec, 1.5, order=1)
        grey = np.clip(128 + 40 * big / np.sqrt(np.mean(big ** 2)), 0, 255).astype(np.uint8)
        _png(d / f"seismic_s{k}.png", np.repeat(grey[..., None], 3, axis=-1), "RGB")
        rgba = np.zeros((h, w, 4), np.uint8)
        rgba[..., 3] = 255 * ndimage.binary_dilation(mask, iterations=1)
        _png(d / f"mask_s{k}.png", rgba, "RGBA")
        truth[f"s{k}"] = (sec, mask)
    smp = s.sample(keys[0])
    write_segy(smp["seismic"] * 1000.0, root / "f3.sgy", x0_m=0.0, cell_m=10.0, top_m=0.0)
    np.save(root / "sec.npy", smp["seismic"])
    np.save(root / "mask.npy", smp["fault"] > 0)
    return root, truth


def test_png_readers_give_back_the_section_and_thin_lines(common, field):
    root, truth = field
    for key, (sec, mask) in truth.items():
        got, m = common["read_pair"](root / "set" / f"seismic_{key}.png",
                                    root / "set" / f"mask_{key}.png", thin_lines=True)
        assert got.shape == sec.shape == m.shape
        assert abs(float(np.sqrt(np.mean(common["read_section"](
            root / "set" / f"seismic_{key}.png") ** 2))) - 1) < 1e-3  # unit RMS
        assert np.corrcoef(got.ravel(), sec.ravel())[0, 1] > 0.9
        drawn = common["read_mask"](root / "set" / f"mask_{key}.png")
        assert drawn.sum() > 2 * mask.sum()                    # drawn 3 px wide
        assert m.sum() < 1.5 * mask.sum()                      # thinned back to about 1 px
        r = common["score_stack"]([m.astype(np.float32)], [mask], 1.0)
        assert r.precision > 0.95 and r.recall > 0.9


def test_scoring_helper_perfect_and_blank(common, field):
    _, truth = field
    masks = [m for _, m in truth.values()] + [np.pad(next(iter(truth.values()))[1], 3)]
    perfect = common["score_stack"]([m.astype(np.float32) for m in masks], masks, 3.0)
    assert perfect.ods_f1 == 1.0 and perfect.ois_f1 == 1.0 and perfect.ap == pytest.approx(1.0)
    blank = common["score_stack"]([np.zeros(m.shape, np.float32) for m in masks], masks, 3.0)
    assert blank.ods_f1 == 0.0 and blank.ois_f1 == 0.0


def test_thin_without_scikit_image(common, monkeypatch):
    import sys

    line = np.zeros((20, 20), bool)
    line[:, 8:11] = True                                       # a vertical line 3 px wide
    monkeypatch.setitem(sys.modules, "skimage.morphology", None)
    thin = common["thin"](line)
    assert thin.sum() == 20 and thin[:, 9].all()


def test_whole_benchmark_on_tiny_stores(bench, field, tiny_store, tmp_path, capsys):
    root, _ = field
    results, fig, cache = tmp_path / "fb.json", tmp_path / "fb.png", tmp_path / "cache"
    argv = ["--store", f"dem={tiny_store}", "--generate", "kin=tiny:3:kinematic",
            "--mix", "mix=dem:1,kin:2", "--field-dir", str(root / "set"),
            "--field", f"npy={root / 'sec.npy'}:{root / 'mask.npy'}", "--f3", str(root / "f3.sgy"),
            "--seeds", "0", "1", "--steps", "2", "--base", "4", "--crop", "32", "--batch", "2",
            "--threads", "1", "--device", "cpu", "--test-fraction", "0.5", "--max-eval", "4",
            "--workers", "0", "--cache", str(cache), "--results", str(results),
            "--figure", str(fig)]
    assert bench["main"](argv) == 0
    out = capsys.readouterr()
    lines = [json.loads(x) for x in out.out.strip().splitlines()]
    assert [x["model"] for x in lines] == ["dem", "kin", "mix"]
    assert out.err.count("training ") == 6 and out.err.count("building kin") == 1
    for line in lines:
        assert line["seeds"] == [0, 1] and line["steps"] == 2 and line["base"] == 4
        assert line["device"] == "cpu" and line["machine"] and line["train_seconds"]["n"] == 2
        assert set(line["field"]) == {"set", "npy"} and set(line["f3"]) == {"1", "auto"}
        assert set(line["synthetic"]) == {"dem", "kin"}
        for scales in line["field"].values():
            for sc in scales.values():
                for m in ("ods_f1", "ois_f1", "ap"):
                    for t in (3, 2):
                        v = sc[f"{m}_tol{t}"]
                        assert v["n"] == 2 and 0 <= v["min"] <= v["mean"] <= v["max"] <= 1
                assert 0 <= sc["share_above_0.5"]["mean"] <= 1
        assert set(line["field"]["set"]["1"]["share_above_0.5_by_section"]) == \
            {p.stem[len("seismic_"):] for p in (root / "set").glob("seismic_*")}
        assert set(line["synthetic"]["kin"]) == {"n_sections"} | {
            f"{m}_tol{t}" for m in ("f1", "ods_f1", "ap") for t in (3, 2)}
    for line in lines:  # the threshold of each model's own held-out runs (pooled for mix)
        at = line["at_heldout_threshold"]
        assert at["n_sections"]["mean"] == sum(
            sc["n_sections"]["mean"] for n, sc in line["synthetic"].items()
            if n in ("dem", "kin") and (n == line["model"] or line["model"] == "mix"))
        assert 0 < at["threshold"]["min"] <= at["threshold"]["max"] < 1
        assert set(at["field"]) == {"set", "npy"} and 0 <= at["f3_share"]["mean"] <= 1
    mix = lines[2]["stores"]
    assert mix[0] == str(tiny_store) and "kin-" in mix[1] and lines[2]["weights"] == [1.0, 2.0]
    assert fig.stat().st_size > 0
    assert len(json.loads(results.read_text())["cells"]) == 6
    # a second visit: one more seed trains only that seed; the built store is reused
    argv[argv.index("--seeds") + 1: argv.index("--seeds") + 3] = ["0", "1", "2"]
    assert bench["main"](argv[:-2]) == 0
    out = capsys.readouterr()
    assert out.err.count("training ") == 3 and "building" not in out.err
    assert all(json.loads(x)["seeds"] == [0, 1, 2] for x in out.out.strip().splitlines())
    # a new tolerance is scored with the saved models, nothing is trained
    assert bench["main"](argv[:-2] + ["--tolerance", "1"]) == 0
    out = capsys.readouterr()
    assert "training " not in out.err
    assert "ods_f1_tol1" in json.loads(out.out.splitlines()[0])["field"]["set"]["auto"]
    # a fixed loss weight is another training: trained anew, recorded in the line and cells
    argv[argv.index("--seeds") + 1: argv.index("--seeds") + 4] = ["0"]
    assert bench["main"](argv[:-2] + ["--pos-weight", "1"]) == 0
    out = capsys.readouterr()
    assert out.err.count("training ") == 3
    assert all(json.loads(x)["pos_weight"] == 1.0 for x in out.out.strip().splitlines())
    cells = json.loads(results.read_text())["cells"]
    assert sorted(c["train"]["pos_weight"] == 1.0 for c in cells) == [False] * 9 + [True] * 3
    # one weight per store of a mix: trained anew, the weights recorded in their order
    mix_argv = [a for a in argv[:-2] if a not in argv[:6]] + [
        "--mix", f"m={tiny_store}:1,{mix[1]}:2", "--pos-weight", "5,1"]
    assert bench["main"](mix_argv) == 0
    out = capsys.readouterr()
    assert out.err.count("training ") == 1
    assert json.loads(out.out)["pos_weight"] == [5.0, 1.0]
    cells = json.loads(results.read_text())["cells"]
    assert [c["train"]["pos_weight"] for c in cells if c["model"] == "m"] == [[5.0, 1.0]]
    with pytest.raises(InputError, match="2 weights for training set 'dem' of 1 store"):
        bench["main"](argv[:-2] + ["--pos-weight", "5,1"])
    # models of separate runs drawn side by side from the cache, nothing trained
    fig2 = runpy.run_path(str(BENCH.with_name("field_models_figure.py")), run_name="fmf")
    out2 = tmp_path / "side.png"
    assert fig2["main"]([f"dem={results}:dem", f"kin={results}:kin", "--seed", "1",
                         "--field", f"s={root / 'sec.npy'}:{root / 'mask.npy'}",
                         "--f3", str(root / "f3.sgy"), "--cache", str(cache),
                         "--out", str(out2)]) == 0
    drawn = json.loads(capsys.readouterr().out)
    assert out2.stat().st_size > 0 and set(drawn["models"]) == {"dem", "kin"}
    assert all(Path(p).parent == cache / "models" for p in drawn["models"].values())
    with pytest.raises(InputError, match="name one as RESULTS:MODEL"):
        fig2["main"]([f"x={results}", "--f3", str(root / "f3.sgy"), "--cache", str(cache),
                      "--out", str(out2)])
    with pytest.raises(InputError, match="trained 2 ways"):  # seed 0: with and without 1
        fig2["main"]([f"x={results}:dem", "--seed", "0", "--f3", str(root / "f3.sgy"),
                      "--cache", str(cache), "--out", str(out2)])
    with pytest.raises(InputError, match="are not in --cache"):
        fig2["main"]([f"x={results}:dem", "--seed", "1", "--f3", str(root / "f3.sgy"),
                      "--cache", str(tmp_path), "--out", str(out2)])


def test_input_errors(bench, common, field, tmp_path):
    root, _ = field
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no seismic_<key>"):
        bench["main"](["--field-dir", str(tmp_path / "empty"), "--store", "a=x"])
    with pytest.raises(InputError, match="field-scale"):
        bench["main"](["--field-scale", "big"])
    np.save(tmp_path / "bad.npy", np.ones((3, 3)))  # a mask, of another shape
    with pytest.raises(InputError, match="shape"):
        common["read_pair"](root / "sec.npy", tmp_path / "bad.npy", thin_lines=False)
    png = next((root / "set").glob("seismic_*"))
    with pytest.raises(InputError, match="shape"):  # a display image of another aspect ratio
        common["read_pair"](png, tmp_path / "bad.npy", thin_lines=False)
    with pytest.raises(InputError, match="no training set"):
        bench["main"](["--cache", str(tmp_path / "c")])
    with pytest.raises(InputError, match="--mix"):
        bench["main"](["--mix", f"m={tmp_path / 'none'}:1", "--cache", str(tmp_path / "c")])


def _has_planar() -> bool:
    from demseis.generator.config.settings import PRESETS

    return "planar" in PRESETS


@pytest.mark.skipif(not _has_planar(), reason="needs the planar engine and preset")
def test_planar_controls_are_built_once_with_their_fault_counts(bench, field, tmp_path, capsys):
    import demseis

    root, _ = field
    argv = ["--planar", "2", "--planar-steep", "2", "--workers", "0", "--cache",
            str(tmp_path / "c"), "--field-dir", str(root / "set"), "--seeds", "0",
            "--steps", "1", "--base", "4", "--crop", "32", "--batch", "2", "--threads", "1",
            "--device", "cpu", "--max-eval", "2", "--field-scale", "1",
            "--results", str(tmp_path / "r.json")]
    assert bench["main"](argv) == 0
    out = capsys.readouterr()
    lines = [json.loads(x) for x in out.out.strip().splitlines()]
    assert [x["model"] for x in lines] == ["planar", "planar_steep"]
    for line, (lo, hi) in zip(lines, ((1, 3), (3, 10))):
        # 2 runs hold none out at --test-fraction 0.25: no held-out scores, and no error
        assert line["synthetic"][line["model"]] == {"n_sections": {
            "mean": 0.0, "std": 0.0, "min": 0.0, "max": 0.0, "n": 1}}
        faults = demseis.open(line["stores"][0]).params["planar_faults"]
        assert lo <= faults.min() and faults.max() <= hi
    assert bench["main"](argv) == 0
    assert "building" not in capsys.readouterr().err


def test_field_sets_and_f3_at_the_threshold_chosen_on_held_out_runs(bench, common, field,
                                                                    tiny_store, tmp_path,
                                                                    capsys):
    """at_heldout_threshold: the threshold that maximises F1 at 2 px on the model's own
    held-out runs, and the field set's F1 and F3's share at it, recomputed here from the saved
    model with demseis.evaluation.score; a results file without them gets them from the saved
    model, with no training."""
    import torch

    from demseis.evaluation import score
    from demseis.learning.model import predict_array
    from demseis.learning.train import build_unet, predict_sections

    root, _ = field
    results, cache = tmp_path / "r.json", tmp_path / "c"
    argv = ["--store", f"dem={tiny_store}", "--field-dir", str(root / "set"),
            "--f3", str(root / "f3.sgy"), "--field-scale", "1", "--seeds", "0",
            "--steps", "6", "--base", "4", "--crop", "32", "--batch", "2", "--threads", "1",
            "--device", "cpu", "--test-fraction", "0.5", "--max-eval", "4",
            "--cache", str(cache), "--results", str(results)]
    assert bench["main"](argv) == 0
    at = json.loads(capsys.readouterr().out.strip())["at_heldout_threshold"]

    (saved,) = (cache / "models").glob("*-0.pt")
    model = build_unet(4)
    model.load_state_dict(torch.load(saved, map_location="cpu", weights_only=True))
    model.eval()
    secs, held = bench["synthetic_test_set"](str(tiny_store), (0.5, 0.0, 0.5), 4)
    ref = score(np.stack(list(predict_sections(model, np.stack(secs)))),
                np.stack(held).astype(np.uint8), tolerance_px=2.0)
    thr = float(ref.ods_threshold)
    assert 0.0 < thr < 1.0 and at["n_sections"]["mean"] == len(secs)
    assert at["threshold"]["mean"] == pytest.approx(thr, abs=1e-4)
    assert at["heldout_f1_tol2"]["mean"] == pytest.approx(float(ref.ods_f1), abs=1e-4)

    maps, masks = _field_maps(common, root, model)
    for tol in (3, 2):
        want = score(np.stack(maps), np.stack(masks).astype(np.uint8), threshold=thr,
                     tolerance_px=float(tol)).f1
        assert at["field"]["set"][f"f1_tol{tol}"]["mean"] == pytest.approx(float(want), abs=1e-4)
    assert at["field"]["set"]["share"]["mean"] == pytest.approx(
        float(np.mean([(m >= thr).mean() for m in maps])), abs=1e-4)
    f3 = predict_array(model, common["read_section"](root / "f3.sgy", "--f3"))
    assert at["f3_share"]["mean"] == pytest.approx(float((f3 >= thr).mean()), abs=1e-4)

    # results written before this score existed: it is added from the saved model (and a
    # figure drawn from it beside)
    data = json.loads(results.read_text())
    for cell in data["cells"]:
        cell["scores"] = {k: v for k, v in cell["scores"].items()
                          if not k.startswith("heldout_threshold:")}
    results.write_text(json.dumps(data))
    assert bench["main"](argv + ["--figure", str(tmp_path / "f.png")]) == 0
    out = capsys.readouterr()
    assert "training " not in out.err and (tmp_path / "f.png").stat().st_size > 0
    assert json.loads(out.out.strip())["at_heldout_threshold"] == at


def test_a_given_model_is_scored_without_training(bench, field, tmp_path, capsys):
    """--model NAME=PATH (the shipped model here) is scored on the field sets and F3 as it
    is: one JSON line, the "auto" scale left out (it needs the training stores' period)."""
    pytest.importorskip("torch")
    from demseis.learning.model import pretrained_path

    root, _ = field
    argv = ["--model", f"shipped={pretrained_path()}", "--field-dir", str(root / "set"),
            "--f3", str(root / "f3.sgy"), "--field-scale", "1", "auto",
            "--results", str(tmp_path / "r.json"), "--cache", str(tmp_path / "c")]
    assert bench["main"](argv) == 0
    out = capsys.readouterr()
    (line,) = [json.loads(x) for x in out.out.strip().splitlines()]
    assert line["model"] == "shipped" and line["trained"]["steps"] == 1200
    assert set(line["field"]) == {"set"} and set(line["field"]["set"]) == {"1"}
    scores = line["field"]["set"]["1"]
    assert 0.0 <= scores["ods_f1_tol3"] <= 1.0 and 0.0 <= scores["share_above_0.5"] <= 1.0
    assert set(line["f3"]) == {"1"} and "training " not in out.err


def test_a_given_model_is_read_at_its_own_threshold(bench, common, field, tmp_path, capsys):
    """A given model that carries a threshold (demseis train saves the one chosen on its
    validation runs) gets at_model_threshold: the field set's F1 at each tolerance, its share
    at or above the threshold and F3's, recomputed here with demseis.evaluation.score."""
    import torch

    from demseis.evaluation import score
    from demseis.learning.model import load_model, predict_array, pretrained_path

    root, _ = field
    blob = torch.load(pretrained_path(), map_location="cpu", weights_only=True)
    path = tmp_path / "m.pt"
    torch.save({**blob, "threshold": 0.3}, path)
    argv = ["--model", f"m={path}", "--field-dir", str(root / "set"), "--f3",
            str(root / "f3.sgy"), "--field-scale", "1", "--results", str(tmp_path / "r.json"),
            "--cache", str(tmp_path / "c")]
    assert bench["main"](argv) == 0
    at = json.loads(capsys.readouterr().out.strip())["at_model_threshold"]
    model = load_model(path, "cpu")
    maps, masks = _field_maps(common, root, model)
    assert at["threshold"] == 0.3
    for tol in (3, 2):
        want = score(np.stack(maps), np.stack(masks).astype(np.uint8), threshold=0.3,
                     tolerance_px=float(tol)).f1
        assert at["field"]["set"][f"f1_tol{tol}"] == pytest.approx(float(want), abs=1e-4)
    assert at["field"]["set"]["share"] == pytest.approx(
        float(np.mean([(m >= 0.3).mean() for m in maps])), abs=1e-4)
    f3 = predict_array(model, common["read_section"](root / "f3.sgy", "--f3"))
    assert at["f3_share"] == pytest.approx(float((f3 >= 0.3).mean()), abs=1e-4)


def test_learning_curve_trains_on_the_first_train_runs(bench, field, tmp_path, capsys,
                                                        monkeypatch):
    """--train-runs: one model per N, each trained on the store's first N train runs only (the
    runs handed to train_unet), all scored on the same held-out runs."""
    import demseis.learning.train as train_mod
    from demseis.datasets import FaultSegDataset
    from tests.generator._helpers import generate_tiny

    root, _ = field
    store = generate_tiny(tmp_path, '[sweep]\nn_runs = 6\n[model]\nengine = "kinematic"\n',
                          "kin")
    capsys.readouterr()
    fr = (0.5, 0.0, 0.5)
    train = np.unique(FaultSegDataset(store, inputs=("seismic",), targets=("fault",),
                                      split="train", split_fractions=fr).run_ids).tolist()
    assert len(train) >= 2
    assert bench["first_train_runs"](str(store), fr, 1) == train[:1]
    with pytest.raises(InputError, match="--train-runs 99"):
        bench["first_train_runs"](str(store), fr, 99)
    seen = []
    original = train_mod.train_unet

    def spy(*a, **k):
        seen.append(k["where"])
        return original(*a, **k)

    monkeypatch.setattr(train_mod, "train_unet", spy)
    argv = ["--store", f"kin={store}", "--train-runs", "1", str(len(train)),
            "--field-dir", str(root / "set"), "--seeds", "0", "--steps", "2", "--base", "4",
            "--crop", "32", "--batch", "2", "--threads", "1", "--device", "cpu",
            "--test-fraction", "0.5", "--max-eval", "4", "--field-scale", "1",
            "--cache", str(tmp_path / "cache"), "--results", str(tmp_path / "fb.json")]
    assert bench["main"](argv) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.strip().splitlines()]
    assert [(x["model"], x["train_runs"]) for x in lines] == [("kin@1", 1),
                                                             (f"kin@{len(train)}", len(train))]
    assert seen == [{"run_id": train[:1]}, {"run_id": train}]
    assert lines[0]["synthetic"].keys() == lines[1]["synthetic"].keys() == {"kin"}
    with pytest.raises(InputError, match="one-store training sets"):
        bench["learning_curve_sets"]({"m": (["a", "b"], [1.0, 1.0])}, [1])


def test_model_threshold_benchmark_reads_at_half_the_model_and_otsu(common, field, tmp_path,
                                                                    capsys):
    """benchmarks/model_threshold.py: F1 of the field set at 0.5, at the model's threshold and
    at Otsu's threshold of each section, and F3's shares, recomputed here with
    demseis.evaluation.score; a group line averages the models named it and a seed."""
    import torch

    from demseis.evaluation import score
    from demseis.learning.model import load_model, predict_array, pretrained_path
    from demseis.plotting import otsu_threshold

    mt = runpy.run_path(str(BENCH.with_name("model_threshold.py")), run_name="model_threshold")
    root, _ = field
    blob = torch.load(pretrained_path(), map_location="cpu", weights_only=True)
    paths = []
    for k, t in enumerate((0.3, 0.8)):
        paths.append(tmp_path / f"m{k}.pt")
        torch.save({**blob, "threshold": t}, paths[-1])
    assert mt["main"]([f"m{k}={p}" for k, p in enumerate(paths)] + [
        "--field-dir", str(root / "set"), "--f3", str(root / "f3.sgy"), "--group", "m"]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.strip().splitlines()]
    assert [x.get("model", x.get("group")) for x in lines] == ["m0", "m1", "m"]
    model = load_model(paths[0], "cpu")
    maps, masks = _field_maps(common, root, model)
    f3 = predict_array(model, common["read_section"](root / "f3.sgy", "--f3"))
    for line, t in zip(lines, (0.3, 0.8)):
        got = line["field"]["set"]
        assert line["threshold"] == t
        for rule, ts in (("0.5", [0.5] * len(maps)), ("model", [t] * len(maps)),
                         ("otsu", [otsu_threshold(m) for m in maps])):
            marks = np.stack([m >= x for m, x in zip(maps, ts)]).astype(np.float32)
            want = score(marks, np.stack(masks).astype(np.uint8), tolerance_px=3.0).f1
            assert got[f"f1_at_{rule}"] == pytest.approx(float(want), abs=1e-4)
            assert got[f"share_at_{rule}"] == pytest.approx(float(marks.mean()), abs=1e-4)
        assert line["f3"]["share_at_model"] == pytest.approx(float((f3 >= t).mean()), abs=1e-4)
    assert lines[0]["f3"]["share_at_0.5"] == pytest.approx(float((f3 >= 0.5).mean()), abs=1e-4)
    group = lines[2]["field"]["set"]
    assert group["f1_at_model"] == pytest.approx(
        np.mean([x["field"]["set"]["f1_at_model"] for x in lines[:2]]), abs=1e-4)
    d = [x["field"]["set"]["f1_at_model"] - x["field"]["set"]["f1_at_0.5"] for x in lines[:2]]
    assert group["model_minus_0.5"]["higher"] == sum(v > 0 for v in d)


def test_a_field_file_is_known_by_its_bytes_not_its_time(bench, tmp_path):
    import os

    f = tmp_path / "f3.sgy"
    f.write_bytes(b"section")
    before = bench["_file_id"](f)
    os.utime(f, (1.0e9, 1.0e9))            # mounted afresh: same bytes, another time
    assert bench["_file_id"](f) == before
    f.write_bytes(b"sectioN")              # same size, other bytes
    assert bench["_file_id"](f) != before
