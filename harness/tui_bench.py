#!/usr/bin/env python3
"""Measure the TUI: terminal bandwidth, render throughput against headless `ptui render`,
and key-to-screen latency. Runs the real binary in a pseudo-terminal of 120x40.

    cargo build --release && python3 harness/tui_bench.py [--seconds 30] [--bin target/release/ptui]
    python3 harness/tui_bench.py --only bandwidth --modes kitty,sixel --ssh localhost

Bandwidth: bytes the program writes to the pty, mean over the last 20 s of a 30 s render of
cornell (320x240, path), in truecolor and in 256-colour mode, or in the `--modes` given (`kitty`
and `sixel` are the pixel preview, `--graphics` forced; the pty reports no pixel size, so cells
of 8x16). With `--ssh HOST` the bandwidth runs go to HOST through `ssh -tt` (key login, the same path
to the binary there) and the bytes counted are those that arrive through the SSH session.
Throughput: samples per second of render time, TUI (from its --bench-log) against headless
`ptui render` at the same settings, alternated in one run.
Latency: time from writing `?` to the pty until the help overlay's bytes arrive, while the
render keeps both cores busy; p50/p99 over many presses.
View (`--only view`): key-to-new-image latency in camera mode on cornell at its default size
(320x240) in a 120x40 pty: single arrow presses at random intervals, and held keys (bursts at
the 33 ms of a key repeat). Each press's latency is from the input thread reading the key to the
flush of the first frame showing a picture of that move or a later one (the TUI's --bench-log
`view` lines); single presses are also timed from the harness's write to the log line showing.
Reload (`--only reload`): time from rewriting the scene file to the `reloaded` status line
arriving on the pty.
"""
import argparse, fcntl, os, pty, re, select, signal, struct, subprocess, sys, tempfile, termios, time, random

def spawn(cmd, env):
    pid, fd = pty.fork()
    if pid == 0:
        fcntl.ioctl(0, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
        os.execvpe(cmd[0], cmd, env)
    return pid, fd

def read_for(fd, seconds, sink):
    """Read everything for `seconds`, appending (time, bytes) to sink."""
    end = time.monotonic() + seconds
    while True:
        left = end - time.monotonic()
        if left <= 0:
            return
        r, _, _ = select.select([fd], [], [], left)
        if r:
            try:
                data = os.read(fd, 1 << 16)
            except OSError:
                return
            if not data:
                return
            sink.append((time.monotonic(), data))

def finish(pid, fd):
    os.write(fd, b"q")
    sink = []
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        done, _ = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        read_for(fd, 0.1, sink)
    else:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    os.close(fd)

def env_for(mode):
    env = dict(os.environ)
    env["TERM"] = "xterm-256color"
    env.pop("COLORTERM", None)
    if mode == "truecolor":
        env["COLORTERM"] = "truecolor"
    return env

def thread_cpu(pid):
    """CPU seconds (user + system) per thread name of a running process."""
    tick = os.sysconf("SC_CLK_TCK")
    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            stat = open(f"/proc/{pid}/task/{tid}/stat").read()
        except OSError:
            continue
        name = stat[stat.index("(") + 1:stat.rindex(")")]
        fields = stat[stat.rindex(")") + 2:].split()
        out[name] = out.get(name, 0.0) + (int(fields[11]) + int(fields[12])) / tick
    return out

CPU = []

SSH = None

def bandwidth(bin, mode, seconds, log):
    cmd = [bin, "cornell", "--spp", "1000000", "--bench-log", log]
    if mode in ("kitty", "sixel"):
        cmd += ["--graphics", mode, "--color", "truecolor"]
    else:
        cmd += ["--color", mode]
    env = env_for(mode)
    if SSH:
        pass_env = [f"TERM={env['TERM']}"] + (["COLORTERM=truecolor"] if "COLORTERM" in env else [])
        cmd = ["ssh", "-tt", "-o", "BatchMode=yes", SSH, "env"] + pass_env + cmd
    pid, fd = spawn(cmd, env)
    t0 = time.monotonic()
    sink = []
    read_for(fd, seconds, sink)
    if not SSH:  # over SSH the local process is the client
        cpu = thread_cpu(pid)
        render = sum(v for k, v in cpu.items() if k.startswith("ptui-render"))
        other = sum(v for k, v in cpu.items() if not k.startswith("ptui-render"))
        CPU.append((render, other))
        print(f"  CPU seconds: render threads {render:.2f}, everything else (UI, worker, input, "
              f"tick) {other:.2f} -> {100 * other / (render + other):.2f}% of the process")
    finish(pid, fd)
    window = 20.0
    start = t0 + seconds - window
    late = sum(len(d) for t, d in sink if t >= start)
    total = sum(len(d) for _, d in sink)
    per_s = []
    for k in range(int(seconds)):
        per_s.append(sum(len(d) for t, d in sink if t0 + k <= t < t0 + k + 1))
    return late / window, total, per_s

def bench_rate(log):
    """samples / render seconds from the last line of a --bench-log."""
    rate = None
    for line in open(log):
        m = re.match(r"t \S+ bytes \d+ samples (\d+) render_secs (\S+)", line)
        if m and float(m.group(2)) > 0:
            rate = int(m.group(1)) / float(m.group(2))
    return rate

def headless_rate(bin, spp, nice):
    cmd = [bin, "render", "cornell", "--spp", str(spp), "--quiet", "-o", os.path.join(tempfile.gettempdir(), "ptui-bench-headless.png")]
    if nice:
        cmd = ["nice", "-n", "10"] + cmd
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    m = re.search(r"([\d.]+) M samples/s", out)
    return float(m.group(1)) * 1e6

def latency(bin, presses, log):
    pid, fd = spawn([bin, "cornell", "--spp", "1000000", "--bench-log", log], env_for("256"))
    sink = []
    read_for(fd, 5, sink)  # let the render get going
    lat = []
    for _ in range(presses):
        buf = b""
        os.write(fd, b"?")
        t0 = time.monotonic()
        got = None
        while time.monotonic() - t0 < 2:
            r, _, _ = select.select([fd], [], [], 0.5)
            if r:
                buf += os.read(fd, 1 << 16)
                if b"this help" in buf:
                    got = time.monotonic() - t0
                    break
        lat.append(got if got is not None else float("inf"))
        os.write(fd, b"x")  # any key closes the help
        read_for(fd, 0.1 + random.random() * 0.2, sink)
    finish(pid, fd)
    return lat

def log_lines(path, prefix):
    try:
        return [float(l.split()[1]) for l in open(path) if l.startswith(prefix + " ")]
    except OSError:
        return []

def view(bin, presses, log):
    """Key-to-new-image latency of camera moves: (single presses, held keys, harness-side)."""
    pid, fd = spawn([bin, "cornell", "--spp", "1000000", "--bench-log", log], env_for("256"))
    sink = []
    read_for(fd, 3, sink)
    os.write(fd, b"v")
    read_for(fd, 0.5, sink)
    left, right = b"\x1b[D", b"\x1b[C"
    singles, outside = [], []
    for k in range(presses):
        seen = len(log_lines(log, "view"))
        os.write(fd, left if k % 2 == 0 else right)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 2:
            read_for(fd, 0.001, sink)
            if len(log_lines(log, "view")) > seen:
                outside.append(time.monotonic() - t0)
                break
        read_for(fd, 0.3 + random.random() * 0.3, sink)
    singles = log_lines(log, "view")
    # Held keys: bursts of 30 repeats 33 ms apart, to the left and back.
    for burst in range(4):
        key = left if burst % 2 == 0 else right
        for _ in range(30):
            os.write(fd, key)
            read_for(fd, 0.033, sink)
        read_for(fd, 1.0, sink)
    held = log_lines(log, "view")[len(singles):]
    finish(pid, fd)
    return singles, held, [x * 1e3 for x in outside]

def reload(bin, edits, tmp):
    """Milliseconds from rewriting the scene file to the frame that shows the reload flushed
    (the TUI's --bench-log `reload` line, seen by polling it)."""
    scene = os.path.join(tmp, "box.toml")
    log = os.path.join(tmp, "reload.log")
    base = open(os.path.join(os.path.dirname(__file__), "..", "scenes", "cornell.toml")).read()
    open(scene, "w").write(base)
    pid, fd = spawn([bin, scene, "--spp", "1000000", "--bench-log", log], env_for("256"))
    sink = []
    read_for(fd, 3, sink)
    lat = []
    count = lambda: sum(1 for l in open(log) if l.strip() == "reload")
    for k in range(edits):
        seen = count()
        open(scene, "w").write(base.replace("emission = 12", f"emission = {12 + (k % 2) + 1}"))
        t0 = time.monotonic()
        while time.monotonic() - t0 < 3:
            read_for(fd, 0.001, sink)
            if count() > seen:
                lat.append(time.monotonic() - t0)
                break
        read_for(fd, 0.4 + random.random() * 0.4, sink)
    finish(pid, fd)
    return [x * 1e3 for x in lat]

def pct(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="target/release/ptui")
    ap.add_argument("--seconds", type=float, default=30)
    ap.add_argument("--presses", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--only", choices=["bandwidth", "throughput", "latency", "view", "reload"])
    ap.add_argument("--modes", default="truecolor,256",
                    help="bandwidth modes, from truecolor, 256, kitty, sixel")
    ap.add_argument("--ssh", metavar="HOST", help="run the TUI on HOST through ssh -tt")
    a = ap.parse_args()
    global SSH
    SSH = a.ssh
    tmp = tempfile.mkdtemp(prefix="ptui-bench-")
    print(f"load average before: {os.getloadavg()}")
    for mode in a.modes.split(",") if a.only in (None, "bandwidth") else []:
        log = os.path.join(tmp, f"bw-{mode}.log")
        mean, total, per_s = bandwidth(a.bin, mode, a.seconds, log)
        print(f"bandwidth {mode}: mean over last 20 s {mean/1000:.1f} KB/s "
              f"(total {total/1000:.0f} KB in {a.seconds:.0f} s; per second KB: "
              f"{' '.join(f'{b/1000:.0f}' for b in per_s)})")
        rate = bench_rate(log)
        if rate:
            print(f"  TUI throughput during that run: {rate/1e6:.3f} M samples/s")
    # Throughput: alternate TUI and headless so machine load hits both alike.
    tui, head, head_nice = [], [], []
    for r in range(a.rounds if a.only in (None, "throughput") else 0):
        log = os.path.join(tmp, f"tp-{r}.log")
        bandwidth(a.bin, "256", a.seconds, log)
        tui.append(bench_rate(log))
        spp = max(8, int(tui[-1] * a.seconds / (320 * 240)))
        head.append(headless_rate(a.bin, spp, False))
        head_nice.append(headless_rate(a.bin, spp, True))
        print(f"round {r}: TUI {tui[-1]/1e6:.3f}, headless {head[-1]/1e6:.3f}, "
              f"headless at nice 10 {head_nice[-1]/1e6:.3f} M samples/s ({spp} spp)")
    if tui:
        report_throughput(tui, head, head_nice)
    if a.only in (None, "latency"):
        report_latency(a, tmp)
    if a.only in (None, "view"):
        singles, held, outside = view(a.bin, a.presses, os.path.join(tmp, "view.log"))
        for name, xs in [("single presses (in-process)", singles),
                         ("single presses (harness write to log line)", outside),
                         ("held keys (in-process)", held)]:
            if xs:
                print(f"key-to-new-image {name}: n {len(xs)}, p50 {pct(xs,50):.1f} ms, "
                      f"p99 {pct(xs,99):.1f} ms, max {max(xs):.1f} ms")
    if a.only in (None, "reload"):
        lat = reload(a.bin, min(a.presses, 40), tmp)
        if lat:
            print(f"file-change-to-reloaded: n {len(lat)}, p50 {pct(lat,50):.0f} ms, "
                  f"p99 {pct(lat,99):.0f} ms, max {max(lat):.0f} ms")
    print(f"load average after: {os.getloadavg()}")

def report_throughput(tui, head, head_nice):
    t, h, hn = sum(tui) / len(tui), sum(head) / len(head), sum(head_nice) / len(head_nice)
    print(f"throughput: TUI {t/1e6:.3f} M/s, headless {h/1e6:.3f} M/s -> {100*t/h:.1f}%; "
          f"against headless at the TUI's nice 10: {hn/1e6:.3f} M/s -> {100*t/hn:.1f}%")

def report_latency(a, tmp):
    lat = latency(a.bin, a.presses, os.path.join(tmp, "lat.log"))
    ms = [x * 1e3 for x in lat]
    print(f"key-to-screen latency over {len(ms)} presses: p50 {pct(ms,50):.1f} ms, "
          f"p99 {pct(ms,99):.1f} ms, max {max(ms):.1f} ms")
    internal = [float(l.split()[1]) for l in open(os.path.join(tmp, "lat.log")) if l.startswith("key ")]
    if internal:
        print(f"  in-process (key read to frame flushed): p50 {pct(internal,50):.2f} ms, "
              f"p99 {pct(internal,99):.2f} ms")

if __name__ == "__main__":
    main()
