#!/usr/bin/env python3
"""Mitsuba 3's BSDF evaluation rate, the anchor of `cargo bench -p uplift --bench engines -- --mitsuba`.

Runs one Mitsuba BSDF's `eval` in the `llvm_ad_rgb` variant (Dr.Jit's LLVM backend, compiled
for this CPU) on N direction pairs already in memory, wv and wl uniform on the upper hemisphere
(the distribution uplift's benchmark draws), and prints one JSON line:
{"bsdf", "variant", "mitsuba", "threads", "points", "rate"} (rate in evals/s, the median of
timed repetitions after a warm-up that JIT-compiles the kernel).

BSDFs: `roughconductor` (gold, GGX alpha 0.3: uplift's `conductor_bsdf` benchmark) and
`principled` with every lobe live (diffuse, metallic specular, dielectric specular, sheen and
clearcoat: the counterpart of the 8-lobe `uplift_stack`). Installed by setup.sh.
"""
import argparse
import json
import statistics
import time

import drjit as dr
import mitsuba as mi

BSDFS = {
    "roughconductor": {"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.3},
    "principled": {
        "type": "principled",
        "base_color": {"type": "rgb", "value": [0.8, 0.5, 0.3]},
        "metallic": 0.5,
        "specular": 0.5,
        "roughness": 0.3,
        "spec_tint": 0.2,
        "sheen": 0.3,
        "sheen_tint": 0.5,
        "clearcoat": 0.5,
        "clearcoat_gloss": 0.8,
    },
}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--bsdf", choices=sorted(BSDFS), required=True)
    p.add_argument("--points", type=int, default=1 << 20)
    p.add_argument("--seconds", type=float, default=2.0)
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args()
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(a.threads)
    bsdf = mi.load_dict(BSDFS[a.bsdf])

    rng = dr.rng(seed=1) if hasattr(dr, "rng") else None
    def uniform():
        if rng is not None:
            return rng.random(mi.Float, a.points)
        return mi.PCG32(size=a.points, initstate=dr.arange(mi.UInt64, a.points)).next_float32()

    def hemisphere():
        z, phi = uniform(), uniform() * (2.0 * dr.pi)
        r = dr.safe_sqrt(1.0 - z * z)
        return mi.Vector3f(r * dr.cos(phi), r * dr.sin(phi), z)

    si = dr.zeros(mi.SurfaceInteraction3f, a.points)
    si.wi = hemisphere()
    si.sh_frame = mi.Frame3f(mi.Vector3f(0.0, 0.0, 1.0))
    si.n = mi.Vector3f(0.0, 0.0, 1.0)
    wo = hemisphere()
    dr.eval(si, wo)
    ctx = mi.BSDFContext()

    def once():
        value = bsdf.eval(ctx, si, wo)
        dr.eval(value)
        dr.sync_thread()

    for _ in range(3):  # JIT compilation and caches
        once()
    times = []
    start = time.perf_counter()
    while time.perf_counter() - start < a.seconds or len(times) < 5:
        t = time.perf_counter()
        once()
        times.append(time.perf_counter() - t)
    rate = a.points / statistics.median(times)
    print(json.dumps({"bsdf": a.bsdf, "variant": "llvm_ad_rgb", "mitsuba": mi.__version__, "threads": a.threads, "points": a.points, "rate": rate}))


if __name__ == "__main__":
    main()
