"""One section under every wavelet, noise kind and processing step (docs/seismic.md).

    PYTHONPATH=. python scripts/survey_look_figure.py --out docs/figures/seismic_survey_look.png

Each panel is one sample of a 1-run kinematic store (the `tiny` preset's model, its last
snapshot) generated with that sample parameter set and everything else at its default, so the
panels differ only in what their titles name. Row 1: the wavelets themselves; rows 2-3: the
sections.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

import demseis
from demseis.generator.config.settings import load_config
from demseis.seismic import Wavelet

#: (title, [sweep] values) of each section panel
PANELS: tuple[tuple[str, dict], ...] = (
    ("Ricker 40 Hz", {}),
    ("Ormsby 2 octaves", {"wavelet": "ormsby"}),
    ("Butterworth 2 octaves", {"wavelet": "butterworth"}),
    ("Ricker rotated -90°", {"wavelet_phase_deg": -90.0}),
    ("Ricker minimum phase", {"wavelet_phase": "minimum"}),
    ("white noise, 5 dB", {"snr_db": 5.0, "noise_kind": "white"}),
    ("band noise, 5 dB", {"snr_db": 5.0, "noise_kind": "band"}),
    ("coloured noise f^-2, 5 dB", {"snr_db": 5.0, "noise_kind": "coloured", "noise_slope": 2.0}),
    ("linear noise, 3 dB", {"linear_noise_snr_db": 3.0, "linear_noise_slope": 1.5}),
    ("gain jitter 0.3 + footprint 0.4", {"trace_gain_jitter": 0.3, "footprint_amplitude": 0.4,
                                          "footprint_period_traces": 12.0}),
    ("AGC 25 samples", {"agc_window_samples": 25}),
    ("clip at 95 %, 4 bits", {"clip_percentile": 95.0, "quantise_bits": 4}),
)


def section(values: dict, work: Path, k: int) -> np.ndarray:
    """The last sample of a 1-run kinematic `tiny` store made with ``values``."""
    raw = load_config(preset="tiny").to_dict()
    raw["model"]["engine"] = "kinematic"
    raw["sweep"].update({"n_runs": 1, **values})
    store = demseis.generate(raw, out=work / f"s{k}.zarr", workers=0, progress=False)
    return np.asarray(store.sample(len(store) - 1)["seismic"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/figures/seismic_survey_look.png")
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 6, figsize=(18, 8.4), gridspec_kw={"height_ratios": [0.7, 1, 1]})
    t = (np.arange(-100, 101)) * 0.0005
    for ax, (title, w) in zip(axes[0], (
            ("Ricker", Wavelet("ricker", 40.0)), ("Ormsby", Wavelet("ormsby", 40.0)),
            ("Butterworth", Wavelet("butterworth", 40.0)),
            ("Ricker -90°", Wavelet("ricker", 40.0, phase_deg=-90.0)),
            ("Ricker minimum", Wavelet("ricker", 40.0, phase="minimum")),
            ("Butterworth minimum", Wavelet("butterworth", 40.0, phase="minimum")))):
        ax.plot(t * 1e3, w.samples(0.0005, 0.1), "k")
        ax.axvline(0, color="0.7", lw=0.5)
        ax.set_title(f"wavelet: {title}", fontsize=9)
        ax.set_xlabel("ms", fontsize=8)
        ax.tick_params(labelsize=7)
    with tempfile.TemporaryDirectory() as tmp:
        for k, (ax, (title, values)) in enumerate(zip(axes[1:].ravel(), PANELS)):
            sec = section(values, Path(tmp), k)
            v = float(np.percentile(np.abs(sec), 99)) or 1.0
            ax.imshow(sec, cmap="gray", vmin=-v, vmax=v, aspect="auto")
            ax.set_title(title, fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            print(f"{title}: rms {float(np.sqrt(np.mean(sec.astype(float) ** 2))):.3g}")
    fig.suptitle("demseis: one kinematic section under each wavelet, noise and processing "
                 "parameter (the rest at their defaults)")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
