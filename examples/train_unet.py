"""Train a small 2D U-Net on a demseis store for a few minutes on CPU, then score it.

Usage::

    python examples/train_unet.py STORE [--minutes 5] [--out-dir runs/unet] [--tolerance 2]

What it does:

1. trains a 3-level U-Net (16-32-64 channels, ~120k parameters) on random crops of the
   ``train`` split of ``demseis.datasets.FaultSegDataset`` (seismic in, fault mask out) with
   binary cross-entropy (positive weight = background/fault pixel ratio, capped at 50) plus soft
   Dice, Adam, for a wall-clock budget;
2. predicts fault probabilities on the whole sections of the ``test`` split (DEM runs never seen
   in training) and writes ``unet_test.npy`` with ``test_indices.npy`` (store index of each row);
3. runs the no-learning baseline (``--baseline-method``, default ``dip``: coherence-weighted
   reflector dip; or ``semblance``) on the same test sections (``baseline_test.npy``);
4. scores both with ``demseis score ... --indices test_indices.npy --by freq_hz,snr_db,dip_deg``
   and prints the tables (CSV and JSON land next to the predictions).

Everything is seeded (``--seed``); on CPU, PyTorch's results are repeatable for a fixed thread
count. The time budget makes the number of steps depend on the machine, so the script prints it.
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time

import numpy as np


def build_unet(base: int = 16):
    """A 3-level 2D U-Net: (B, 1, H, W) seismic -> (B, 1, H, W) fault logits (H, W % 4 == 0)."""
    import torch
    from torch import nn

    def block(cin: int, cout: int) -> nn.Sequential:
        return nn.Sequential(
            nn.Conv2d(cin, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(True),
            nn.Conv2d(cout, cout, 3, padding=1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(True),
        )

    class UNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.enc1, self.enc2, self.mid = block(1, base), block(base, 2 * base), \
                block(2 * base, 4 * base)
            self.pool = nn.MaxPool2d(2)
            self.up2 = nn.ConvTranspose2d(4 * base, 2 * base, 2, stride=2)
            self.dec2 = block(4 * base, 2 * base)
            self.up1 = nn.ConvTranspose2d(2 * base, base, 2, stride=2)
            self.dec1 = block(2 * base, base)
            self.head = nn.Conv2d(base, 1, 1)

        def forward(self, x: torch.Tensor) -> torch.Tensor:
            # amplitude scale differs between sections: standardise each one
            x = (x - x.mean(dim=(2, 3), keepdim=True)) / (x.std(dim=(2, 3), keepdim=True) + 1e-6)
            e1 = self.enc1(x)
            e2 = self.enc2(self.pool(e1))
            m = self.mid(self.pool(e2))
            d2 = self.dec2(torch.cat([self.up2(m), e2], 1))
            d1 = self.dec1(torch.cat([self.up1(d2), e1], 1))
            return self.head(d1)

    return UNet()


def predict_sections(model, sections: np.ndarray, batch: int = 4) -> np.ndarray:
    """Fault probabilities (N, H, W) float32 of seismic sections (N, H, W), padded to % 4."""
    import torch

    n, h, w = sections.shape
    ph, pw = (-h) % 4, (-w) % 4
    out = np.empty((n, h, w), np.float32)
    model.eval()
    with torch.no_grad():
        for s in range(0, n, batch):
            x = torch.from_numpy(np.ascontiguousarray(sections[s : s + batch], np.float32))[:, None]
            x = torch.nn.functional.pad(x, (0, pw, 0, ph), mode="reflect")
            out[s : s + batch] = torch.sigmoid(model(x))[:, 0, :h, :w].numpy()
    return out


def train(args: argparse.Namespace) -> tuple[object, dict]:
    """Train for ``args.minutes`` of wall clock; returns the model and a log dict."""
    import torch
    from torch.utils.data import DataLoader

    from demseis.datasets import FaultSegDataset

    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    ds = FaultSegDataset(args.store, inputs=("seismic",), targets=("fault",), split="train",
                         crop=(args.crop, args.crop), seed=args.seed)
    if len(ds) == 0:
        raise SystemExit("the train split of the store is empty")
    h, w = ds.layout.shape
    if args.crop > min(h, w) or args.crop % 4:
        raise SystemExit(f"--crop must be a multiple of 4 and at most {min(h, w)}")
    gen = torch.Generator().manual_seed(args.seed)
    loader = DataLoader(ds, batch_size=args.batch, shuffle=True, generator=gen, drop_last=False)
    # fault pixels are rare: weight them by the background / fault ratio of a few batches
    frac = np.mean([float(y.float().mean()) for _, (_, y) in zip(range(8), loader)])
    pos_weight = torch.tensor(min((1 - frac) / max(frac, 1e-6), 50.0))
    model = build_unet(args.base)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    bce = torch.nn.BCEWithLogitsLoss(pos_weight=pos_weight)
    t0, step, epoch, losses = time.perf_counter(), 0, 0, []
    budget = 60.0 * args.minutes
    print(f"train: {len(ds)} samples ({len(np.unique(ds.run_ids))} runs), crop {args.crop}, "
          f"fault fraction {frac:.4f}, pos_weight {float(pos_weight):.1f}, budget "
          f"{args.minutes:g} min", flush=True)
    while time.perf_counter() - t0 < budget:
        ds.set_epoch(epoch)
        model.train()
        for x, y in loader:
            y = y.float()[:, None]
            logits = model(x)
            p = torch.sigmoid(logits)
            dice = 1 - (2 * (p * y).sum() + 1) / (p.sum() + y.sum() + 1)
            loss = bce(logits, y) + dice
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(float(loss.detach()))
            step += 1
            if step % 20 == 0:
                print(f"  step {step:5d}  epoch {epoch:3d}  loss {np.mean(losses[-20:]):.4f}  "
                      f"{time.perf_counter() - t0:6.0f} s", flush=True)
            if time.perf_counter() - t0 >= budget:
                break
        epoch += 1
    log = {"steps": step, "epochs": epoch, "seconds": time.perf_counter() - t0,
           "final_loss": float(np.mean(losses[-20:])) if losses else float("nan")}
    print(f"trained {step} steps ({epoch} epochs) in {log['seconds']:.0f} s, "
          f"final loss {log['final_loss']:.4f}", flush=True)
    return model, log


def run_score(pred: str, store: str, indices: str, tolerance: float, by: str,
              bins: int) -> int:
    """``demseis score`` on predictions of the test samples (printed as a command line)."""
    from demseis.cli import main

    argv = ["score", pred, store, "--indices", indices, "--tolerance", f"{tolerance:g}",
            "--by", by, "--bins", str(bins)]
    print("\n$ demseis " + " ".join(shlex.quote(a) for a in argv), flush=True)
    return main(argv)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("store", help="demseis store (from `demseis generate`)")
    ap.add_argument("--out-dir", default="runs/unet", help="where predictions and scores go")
    ap.add_argument("--minutes", type=float, default=5.0, help="training wall-clock budget")
    ap.add_argument("--crop", type=int, default=96, help="training crop size (multiple of 4)")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--base", type=int, default=16, help="channels of the first U-Net level")
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--tolerance", type=float, default=2.0, help="scoring tolerance in pixels")
    ap.add_argument("--by", default="freq_hz,snr_db,dip_deg", help="scoring breakdown")
    ap.add_argument("--bins", type=int, default=3, help="bins of drawn parameters (dip)")
    ap.add_argument("--baseline-method", choices=("dip", "semblance"), default="dip")
    args = ap.parse_args(argv)

    import torch

    from demseis.datasets import FaultSegDataset
    from demseis.evaluation.baseline import baseline_fault_probability

    os.makedirs(args.out_dir, exist_ok=True)
    model, _ = train(args)
    torch.save(model.state_dict(), os.path.join(args.out_dir, "unet.pt"))

    test = FaultSegDataset(args.store, inputs=("seismic",), targets=("fault",), split="test")
    if len(test) == 0:
        raise SystemExit("the test split of the store is empty")
    seis = np.stack([test[i][0][0].numpy() for i in range(len(test))])
    idx_path = os.path.join(args.out_dir, "test_indices.npy")
    np.save(idx_path, test.indices)
    unet_path = os.path.join(args.out_dir, "unet_test.npy")
    np.save(unet_path, predict_sections(model, seis))
    base_path = os.path.join(args.out_dir, "baseline_test.npy")
    np.save(base_path, baseline_fault_probability(seis, args.baseline_method))
    print(f"\npredicted {len(test)} test sections ({len(np.unique(test.run_ids))} runs)")
    rc = run_score(base_path, args.store, idx_path, args.tolerance, args.by, args.bins)
    rc = rc or run_score(unet_path, args.store, idx_path, args.tolerance, args.by, args.bins)
    return rc


if __name__ == "__main__":
    sys.exit(main())
