"""What the Mitsuba reference harnesses share: the mean of independent passes, its noise estimate,
and the reference written atomically with its `.txt` summary (docs/REFERENCES.md)."""

import math
import os
import sys
import tempfile
import time

import numpy as np


def atomic_write_text(path, text):
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path) or ".", suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.chmod(tmp, 0o644)  # mkstemp makes it private
    os.replace(tmp, path)


class Passes:
    """The mean of `n` independent passes (seeds first_seed..) and each pixel's standard error
    from their spread."""

    def __init__(self, mi, scene, spp, n, first_seed):
        self.spp, self.n, self.first_seed = spp, n, first_seed
        total = total2 = None
        t0 = time.time()
        for k in range(n):
            img = np.array(mi.render(scene, seed=first_seed + k, spp=spp), dtype=np.float64)
            img = img[:, :, :3]
            if not np.isfinite(img).all():
                sys.exit(f"pass {k}: non-finite pixels")
            total = img.copy() if total is None else total + img
            total2 = img * img if total2 is None else total2 + img * img
            print(
                f"pass {k + 1}/{n}: means {img.reshape(-1, 3).mean(0)} "
                f"({time.time() - t0:.0f} s)",
                flush=True,
            )
        self.seconds = time.time() - t0
        self.mean = total / n
        # Unbiased variance of one pass across passes; the mean's is that over n.
        var_pass = np.maximum(total2 - n * self.mean * self.mean, 0) / (n - 1)
        self.noise_rmse = math.sqrt((var_pass / n).mean())
        h, w = self.mean.shape[:2]
        self.channel_means = self.mean.reshape(-1, 3).mean(0)
        # Standard error of each channel's image mean, from the passes' image means.
        self.channel_se = np.sqrt(var_pass.reshape(-1, 3).sum(0)) / (h * w) / math.sqrt(n)

    def write(self, mi, out, root, script, lines):
        """The mean image to `out` (float32 EXR) and its summary next to it (`.txt`): `lines`
        (key = value strings) first, then size, spp, time, means and the noise estimate."""
        os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
        bmp = mi.Bitmap(self.mean.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
        tmp = out + ".tmp.exr"
        bmp.write(tmp)
        os.replace(tmp, out)
        h, w = self.mean.shape[:2]
        m, se, n = self.channel_means, self.channel_se, self.n
        seeds = f"seeds {self.first_seed}..{self.first_seed + n - 1}"
        stats = (
            f"# {os.path.basename(out)}: written by {os.path.relpath(script, root)}; do not edit\n"
            + "".join(f"{line}\n" for line in lines)
            + f"size = {w}x{h}\n"
            f"spp = {self.spp * n} ({n} independent passes of {self.spp}, {seeds})\n"
            f"seconds = {self.seconds:.0f} ({os.cpu_count()} cores)\n"
            f"mean = {m[0]:.6f} {m[1]:.6f} {m[2]:.6f}\n"
            f"mean_standard_error = {se[0]:.7f} {se[1]:.7f} {se[2]:.7f}\n"
            f"noise_rmse = {self.noise_rmse:.6f}\n"
        )
        atomic_write_text(os.path.splitext(out)[0] + ".txt", stats)
        print(stats, end="")
