#!/usr/bin/env python3
"""PyTorch's rates for uplift's neural networks, the anchor of `cargo bench -p uplift --bench
neural -- --torch`.

The same networks, batch and work per sample as runtime/neural (model.rs, trainer.rs, fit.rs):
- encoder: P -> 64 -> 64 -> 64 -> L (leaky ReLU 0.01, sigmoid head);
- decoder: L + 9 -> 64 -> 64 -> 64 -> 64 -> 7 (leaky ReLU 0.01, head exp(min(x, 30) - 3));
- training step: encoder -> uniform latent jitter +-0.005 -> decoder -> Eq. 3 (L1 of
  ln(1 + mu_l f) against ln(1 + target), L1 of T and R, weights 0.95 / 0.04 / 0.01) ->
  backward -> Adam on both networks;
- latent-fitting step: the frozen decoder's forward and backward to the latents (no weight
  gradients) and Adam on the latents;
- inference: the decoder's forward pass under torch.inference_mode().
Inputs are random (uniform) rows of the right shapes: the rates do not depend on their values.
Prints one JSON line {"torch", "threads", "rows", "train", "fit", "infer"} (rows/s, each the
median of seven timed windows after a warm-up, as the Rust benchmark measures).
"""
import argparse
import json
import statistics
import time

import torch


def mlp(widths):
    layers = []
    for k in range(len(widths) - 1):
        layers.append(torch.nn.Linear(widths[k], widths[k + 1]))
        if k + 2 < len(widths):
            layers.append(torch.nn.LeakyReLU(0.01))
    return torch.nn.Sequential(*layers)


def exp_head(x):
    return torch.exp(torch.clamp(x, max=30.0) - 3.0)


def eq3(out, target, mu_l):
    f = torch.log1p(mu_l * out[:, :3]) - torch.log1p(target[:, :3].clamp(min=0.0))
    return 0.95 * f.abs().mean() + 0.04 * (out[:, 3:6] - target[:, 3:6]).abs().mean() + 0.01 * (out[:, 6] - target[:, 6]).abs().mean()


def rate(rows, seconds, step):
    step()
    windows = []
    for _ in range(7):
        start, n = time.perf_counter(), 0
        while time.perf_counter() - start < seconds / 7.0 or n < 2:
            step()
            n += 1
        windows.append(n * rows / (time.perf_counter() - start))
    return statistics.median(windows)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=16384)
    ap.add_argument("--params", type=int, default=22)
    ap.add_argument("--latent", type=int, default=6)
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", default=None)
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(1)
    n, latent = a.rows, a.latent
    encoder, decoder = mlp([a.params, 64, 64, 64, latent]), mlp([latent + 9, 64, 64, 64, 64, 7])
    params = torch.rand(n, a.params)
    features = torch.rand(n, 9)
    target = torch.rand(n, 7)
    mu_l = torch.rand(n, 1)
    out = {"torch": torch.__version__, "threads": a.threads, "rows": n}
    wants = lambda what: a.only is None or a.only == what

    if wants("train"):
        opt = torch.optim.Adam(list(encoder.parameters()) + list(decoder.parameters()), lr=1e-3)

        def train():
            opt.zero_grad(set_to_none=True)
            z = torch.sigmoid(encoder(params)) + (torch.rand(n, latent) - 0.5) * 0.01
            loss = eq3(exp_head(decoder(torch.cat([z, features], 1))), target, mu_l)
            loss.backward()
            opt.step()

        out["train"] = rate(n, a.seconds, train)

    for p in decoder.parameters():
        p.requires_grad_(False)
    if wants("fit"):
        z = torch.full((n, latent), 0.5, requires_grad=True)
        opt = torch.optim.Adam([z], lr=1e-3)

        def fit():
            opt.zero_grad(set_to_none=True)
            loss = eq3(exp_head(decoder(torch.cat([z, features], 1))), target, mu_l)
            loss.backward()
            opt.step()

        out["fit"] = rate(n, a.seconds, fit)

    if wants("infer"):
        x = torch.cat([torch.rand(n, latent), features], 1)

        def infer():
            with torch.inference_mode():
                exp_head(decoder(x))

        out["infer"] = rate(n, a.seconds, infer)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
