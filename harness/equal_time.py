#!/usr/bin/env python3
"""Equal-time error against Mitsuba 3: ptui's default render and Mitsuba's `path` integrator on
the same scene for the same wall time, each one's RMSE against the scene's high-spp reference.

Run through harness/equal_time.sh (it sets up Mitsuba's environment and builds ptui). Runs
alternate, ptui then Mitsuba, `--pairs` times (pair k: ptui's seed k, Mitsuba's 1,000,000 + k, apart from its reference's), so that a change in the machine's load touches
both sides alike. Both render on `--threads` threads, and both times leave out the scene build:

- ptui: `ptui converge SCENE --integrator path --reference REF --seconds S` (the scene's own
  settings: Sobol samples, adaptive sampling, light-traced caustics where the scene allows); its
  last checkpoint is the measurement (render time only, scene build and checkpoints excluded).
- Mitsuba: harness/mitsuba_mesh.py --time-spp N, N calibrated once so that a render takes about S
  seconds; the scene load and a first, untimed render that compiles the kernels are left out.

Each RMSE is scaled to exactly S seconds by sqrt(t / S) (error falls like 1/sqrt(time); the
runs are within a few per cent of S), and the reference's own noise is taken out in quadrature.
"""

import argparse
import csv
import math
import os
import statistics
import subprocess
import sys
import tempfile

here = os.path.dirname(os.path.abspath(__file__))
# Beyond the seeds any reference uses (passes 0..N-1, N in the hundreds).
REF_SEEDS_END = 1_000_000
root = os.path.dirname(here)


def noise_rmse(ref):
    txt = os.path.splitext(ref)[0] + ".txt"
    with open(txt) as f:
        for line in f:
            if line.startswith("noise_rmse = "):
                return float(line.split("=")[1])
    sys.exit(f"{txt}: no noise_rmse line")


def size_of(ref):
    txt = os.path.splitext(ref)[0] + ".txt"
    with open(txt) as f:
        for line in f:
            if line.startswith("size = "):
                w, h = line.split("=")[1].strip().split("x")
                return int(w), int(h)
    sys.exit(f"{txt}: no size line")


def run_ptui(args, size, out, seed):
    cmd = [
        args.ptui, "converge", args.scene,
        "--seed", str(seed),
        "--integrator", "path",
        "--reference", args.reference,
        "--seconds", str(args.seconds),
        "--threads", str(args.threads),
        "--size", f"{size[0]}x{size[1]}",
        "-q", "-o", out,
    ]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "convergence.csv")) as f:
        rows = list(csv.DictReader(f))
    last = rows[-1]
    seconds = float(last["seconds"])
    if seconds < 0.9 * args.seconds:
        sys.exit(
            f"ptui stopped at {seconds:.2f} s ({last['spp']} spp): the scene's spp limit came "
            f"before {args.seconds} s"
        )
    return seconds, float(last["rmse"]), last["spp"]


def run_mitsuba(args, spp, seed):
    cmd = [
        sys.executable, os.path.join(here, "mitsuba_mesh.py"), args.scene,
        "--width", str(args.size[0]), "--height", str(args.size[1]),
        "--variant", args.variant, "--threads", str(args.threads),
        "--time-spp", str(spp), "--seed", str(seed), "--reference", args.reference,
    ]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    for line in out.splitlines():
        if line.startswith("scene load"):
            warm = line
        if line.startswith("mitsuba "):
            f = line.split()
            return float(f[f.index("seconds") + 1]), float(f[f.index("rmse") + 1]), warm
    sys.exit(f"no timing line from Mitsuba:\n{out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="ptui scene file (the reference's)")
    ap.add_argument("reference", help="reference EXR with its .txt (noise_rmse, size)")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variant", default="llvm_ad_rgb", choices=["llvm_ad_rgb", "scalar_rgb"])
    ap.add_argument("--mitsuba-spp", type=int, help="skip the calibration: Mitsuba's spp")
    ap.add_argument("--ptui", default=os.path.join(root, "target", "release", "ptui"))
    args = ap.parse_args()
    args.size = size_of(args.reference)
    noise = noise_rmse(args.reference)

    spp = args.mitsuba_spp
    if spp is None:
        probe = 16
        t, _, _ = run_mitsuba(args, probe, REF_SEEDS_END - 1)
        spp = max(1, round(probe * args.seconds / t))
        print(f"calibration: {probe} spp in {t:.2f} s -> {spp} spp for {args.seconds} s", flush=True)

    def scaled(rmse, t):
        ours = math.sqrt(max(rmse * rmse - noise * noise, 0.0))
        return rmse * math.sqrt(t / args.seconds), ours * math.sqrt(t / args.seconds)

    ratios_raw, ratios = [], []
    print(f"{args.scene}, {args.size[0]}x{args.size[1]}, {args.threads} threads, reference noise {noise}")
    for k in range(args.pairs):
        with tempfile.TemporaryDirectory() as out:
            pt, pr, pspp = run_ptui(args, args.size, out, k)
        # Seeds far from the reference's passes (0, 1, ...), whose random numbers these would share.
        mt, mr, warm = run_mitsuba(args, spp, REF_SEEDS_END + k)
        p_raw, p = scaled(pr, pt)
        m_raw, m = scaled(mr, mt)
        ratios_raw.append(p_raw / m_raw)
        ratios.append(p / m)
        print(
            f"pair {k + 1}: ptui {pt:.2f} s {pspp} spp rmse {pr:.5f} | "
            f"mitsuba {args.variant} {mt:.2f} s {spp} spp rmse {mr:.5f} ({warm}) | "
            f"at {args.seconds:g} s: ptui {p_raw:.5f} / mitsuba {m_raw:.5f} = {p_raw / m_raw:.3f}, "
            f"noise removed {p:.5f} / {m:.5f} = {p / m:.3f}",
            flush=True,
        )
    for name, r in (("ratio ptui/mitsuba", ratios_raw), ("noise removed", ratios)):
        print(f"{name}: min {min(r):.3f} median {statistics.median(r):.3f} max {max(r):.3f}")


if __name__ == "__main__":
    main()
