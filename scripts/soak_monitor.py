#!/usr/bin/env python3
"""Soak monitor (issue 19): samples a running pipeline and judges it.

Run by scripts/soak.sh with Debian's /usr/bin/python3 (rospy). Every --interval seconds it
records the resident memory (VmRSS) of every process under the launch (--pid, the roslaunch
process), the message rates of a few light topics, and the worst /diagnostics level per status.
After --minutes it writes into --out:
  soak.csv          one row per sample (time, total RSS, RSS per process, rates, diagnostics)
  soak.svg          memory and rates over time
  soak_summary.txt  the verdict: RSS growth after the warm-up (the slope of a linear fit over
                    the judged samples times their span, as a share of the first judged RSS)
                    < --max-growth,
                    total RSS < --max-rss-mb, pSfS frame sets waiting never above its queue, no
                    /diagnostics status at ERROR or STALE after the warm-up (WARNs are listed)
and exits 0 when everything holds, 1 otherwise.
"""
import argparse
import os
import sys
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from proc_tree import label_of, processes_of, rss_mb  # noqa: E402

LEVELS = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}


class Counter:
    def __init__(self, topic):
        self.topic = topic
        self.count = 0
        self.lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, rospy.AnyMsg, self.on_msg, queue_size=50, tcp_nodelay=True)

    def on_msg(self, _):
        with self.lock:
            self.count += 1

    def take(self):
        with self.lock:
            c, self.count = self.count, 0
        return c


class Diagnostics:
    def __init__(self):
        self.lock = threading.Lock()
        self.window = {}  # name -> (worst level, its message) since the last take()
        self.values = {}  # (name, key) -> latest value
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_msg, queue_size=100)

    def on_msg(self, msg):
        with self.lock:
            for s in msg.status:
                level = int.from_bytes(s.level, "little") if isinstance(s.level, bytes) else int(s.level)
                worst = self.window.get(s.name)
                if worst is None or level > worst[0]:
                    self.window[s.name] = (level, s.message)
                for kv in s.values:
                    self.values[(s.name, kv.key)] = kv.value

    def take(self):
        with self.lock:
            w, self.window = self.window, {}
            return w, dict(self.values)


def svg_plot(samples, processes, rate_topics, path, warmup):
    """Two panels (RSS in MB; rates in Hz) against minutes, as plain SVG."""
    W, H, L, R, T, G = 900, 560, 70, 220, 30, 60
    ph = (H - T - 2 * G) / 2
    t_end = max(s["t"] for s in samples) or 1.0
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>']

    def panel(y0, title, series, unit):
        vmax = max([max(v for _, v in pts) for _, pts in series if pts] + [1e-9]) * 1.1
        out.append(f'<text x="{L}" y="{y0 - 8}" font-weight="bold">{title}</text>')
        out.append(f'<rect x="{L}" y="{y0}" width="{W - L - R}" height="{ph}" fill="none" stroke="#999"/>')
        for k in range(5):
            v = vmax * k / 4
            y = y0 + ph - ph * k / 4
            out.append(f'<text x="{L - 6}" y="{y + 4}" text-anchor="end">{v:.0f}</text>')
            out.append(f'<line x1="{L}" x2="{W - R}" y1="{y}" y2="{y}" stroke="#eee"/>')
        for k in range(6):
            t = t_end * k / 5
            x = L + (W - L - R) * k / 5
            out.append(f'<text x="{x}" y="{y0 + ph + 16}" text-anchor="middle">{t / 60:.1f} min</text>')
        xw = L + (W - L - R) * min(warmup, t_end) / t_end
        out.append(f'<line x1="{xw}" x2="{xw}" y1="{y0}" y2="{y0 + ph}" stroke="#bbb" stroke-dasharray="4 3"/>')
        for i, (name, pts) in enumerate(series):
            if not pts:
                continue
            c = colours[i % len(colours)]
            d = " ".join(f"{L + (W - L - R) * t / t_end:.1f},{y0 + ph - ph * v / vmax:.1f}" for t, v in pts)
            out.append(f'<polyline points="{d}" fill="none" stroke="{c}" stroke-width="1.5"/>')
            out.append(f'<text x="{W - R + 10}" y="{y0 + 14 + 16 * i}" fill="{c}">{name} ({unit})</text>')

    mem = [("total", [(s["t"], s["total"]) for s in samples])]
    mem += [(p, [(s["t"], s["rss"].get(p, 0.0)) for s in samples]) for p in processes]
    panel(T + 10, "resident memory (MB); dashed: end of the warm-up", mem, "MB")
    rates = [(t, [(s["t"], s["rates"].get(t, 0.0)) for s in samples]) for t in rate_topics]
    panel(T + 10 + ph + G, "message rates (Hz)", rates, "Hz")
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def fit_growth(points):
    """Least-squares slope (MB/s) of (t, MB) points."""
    n = len(points)
    if n < 2:
        return 0.0
    mt = sum(t for t, _ in points) / n
    mv = sum(v for _, v in points) / n
    den = sum((t - mt) ** 2 for t, _ in points)
    return sum((t - mt) * (v - mv) for t, v in points) / den if den > 0 else 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pid", type=int, required=True, help="roslaunch's PID: its process tree is measured")
    ap.add_argument("--minutes", type=float, default=60.0, help="length of the soak (default 60)")
    ap.add_argument("--warmup", type=float, default=300.0, help="seconds not judged at the start (default 300)")
    ap.add_argument("--interval", type=float, default=10.0, help="seconds between samples (default 10)")
    ap.add_argument("--out", default="soak", help="output folder (default ./soak)")
    ap.add_argument("--ns", default="/tabletop", help="the pipeline's namespace (default /tabletop)")
    ap.add_argument("--max-growth", type=float, default=1.0, help="RSS growth bar after the warm-up, %% (default 1)")
    ap.add_argument("--max-rss-mb", type=float, default=1536.0, help="total RSS bar, MB (default 1536)")
    ap.add_argument("--queue", type=int, default=2, help="pSfS queue_size: frame sets waiting never above it")
    ap.add_argument("--allow-warn", default="dropping frame sets,load shedding",
                    help="comma-separated WARN messages (prefixes) that do not fail the soak")
    a = ap.parse_args(rospy.myargv()[1:])
    os.makedirs(a.out, exist_ok=True)
    rospy.init_node("soak_monitor", anonymous=True, disable_signals=True)
    # Light topics only (a header or a few poses per set): the monitor must not load the pipeline
    # it measures. psfs/processed: one per frame set pSfS finished.
    rate_topics = [a.ns + t for t in ("/psfs/processed", "/hands/targets", "/body/pose", "/cve/hand_meshes")]
    counters = [Counter(t) for t in rate_topics]
    diags = Diagnostics()
    samples, processes = [], []
    bad_diag, warns, max_waiting = {}, {}, 0
    t0 = time.monotonic()
    next_t = t0 + a.interval
    total_s = a.minutes * 60.0
    allowed = [w.strip() for w in a.allow_warn.split(",") if w.strip()]
    print(f"[soak] measuring the process tree of PID {a.pid} for {a.minutes:g} min "
          f"(warm-up {a.warmup:g} s, a sample every {a.interval:g} s) into {a.out}", flush=True)
    while True:
        time.sleep(max(0.0, next_t - time.monotonic()))
        now = time.monotonic()
        dt = now - (next_t - a.interval)
        next_t += a.interval
        t = now - t0
        if not os.path.exists(f"/proc/{a.pid}"):
            print("[soak] the launch has ended early", flush=True)
            break
        rss = {}
        for pid in processes_of(a.pid):
            name = label_of(pid)
            if name:
                rss[name] = rss.get(name, 0.0) + rss_mb(pid)
        rates = {c.topic: c.take() / dt for c in counters}
        window, values = diags.take()
        waiting = [int(float(v)) for (n, k), v in values.items() if k == "frame sets waiting"]
        if t > a.warmup:
            max_waiting = max([max_waiting] + waiting)
            for name, (level, message) in window.items():
                if level >= 2:
                    bad_diag[name] = f"{LEVELS.get(level, level)}: {message}"
                elif level == 1 and not any(message.startswith(p) for p in allowed):
                    warns[name] = message
        s = {"t": t, "total": sum(rss.values()), "rss": rss, "rates": rates,
             "worst": max([lv for lv, _ in window.values()] + [0])}
        samples.append(s)
        for p in sorted(rss, key=lambda k: -rss[k]):
            if p not in processes:
                processes.append(p)
        rate_text = ", ".join(f"{k.split('/')[-1]} {v:.1f}" for k, v in rates.items())
        print(f"[soak] {t / 60:5.1f} min: RSS {s['total']:.0f} MB ({len(rss)} processes), Hz: {rate_text}, "
              f"diagnostics worst {LEVELS.get(s['worst'])}", flush=True)
        if t >= total_s:
            break
    rospy.signal_shutdown("done")
    top = processes[:6]
    with open(os.path.join(a.out, "soak.csv"), "w") as f:
        f.write("t_s,total_rss_mb," + ",".join(f"rss_mb:{p}" for p in top) + "," +
                ",".join(f"hz:{t}" for t in rate_topics) + ",diagnostics_worst\n")
        for s in samples:
            f.write(f"{s['t']:.1f},{s['total']:.1f}," + ",".join(f"{s['rss'].get(p, 0.0):.1f}" for p in top) + "," +
                    ",".join(f"{s['rates'].get(t, 0.0):.2f}" for t in rate_topics) + f",{LEVELS.get(s['worst'])}\n")
    if samples:
        svg_plot(samples, top, rate_topics, os.path.join(a.out, "soak.svg"), a.warmup)
    judged = [(s["t"], s["total"]) for s in samples if s["t"] > a.warmup]
    lines, ok = [], True
    duration = samples[-1]["t"] if samples else 0.0
    lines.append(f"soak of {duration / 60:.1f} min, warm-up {a.warmup:.0f} s, {len(samples)} samples")
    if len(judged) < 2 or duration < total_s * 0.95:
        lines.append("FAIL: the run ended before its time (see the launch log)" if duration < total_s * 0.95
                     else "FAIL: too few samples after the warm-up")
        ok = False
    else:
        slope = fit_growth(judged)
        first = judged[0][1]
        growth = 100.0 * slope * (judged[-1][0] - judged[0][0]) / first if first > 0 else 0.0
        peak = max(s["total"] for s in samples)
        lines.append(f"RSS after the warm-up {first:.0f} MB, at the end {judged[-1][1]:.0f} MB, peak {peak:.0f} MB; "
                     f"fitted growth {growth:+.2f} % over {(judged[-1][0] - judged[0][0]) / 60:.1f} min "
                     f"({slope * 3600:+.1f} MB/h)")
        for p in top:
            pts = [(s["t"], s["rss"].get(p, 0.0)) for s in samples if s["t"] > a.warmup]
            lines.append(f"  {p}: {pts[0][1]:.0f} -> {pts[-1][1]:.0f} MB ({fit_growth(pts) * 3600:+.1f} MB/h)")
        if growth >= a.max_growth:
            lines.append(f"FAIL: RSS grew {growth:.2f} % (bar {a.max_growth:g} %)")
            ok = False
        if peak >= a.max_rss_mb:
            lines.append(f"FAIL: RSS peaked at {peak:.0f} MB (bar {a.max_rss_mb:g} MB)")
            ok = False
    judged_rates = [s["rates"] for s in samples if s["t"] > a.warmup]
    for topic in rate_topics:
        r = [x.get(topic, 0.0) for x in judged_rates]
        if r:
            lines.append(f"rate {topic}: mean {sum(r) / len(r):.1f} Hz, min {min(r):.1f} Hz")
    lines.append(f"pSfS frame sets waiting: at most {max_waiting} (queue {a.queue})")
    if max_waiting > a.queue:
        lines.append("FAIL: a queue grew beyond its size")
        ok = False
    for name, text in sorted(bad_diag.items()):
        lines.append(f"FAIL: /diagnostics '{name}' {text}")
        ok = False
    for name, text in sorted(warns.items()):
        lines.append(f"note: /diagnostics '{name}' WARN: {text}")
    lines.append("PASS" if ok else "FAIL")
    with open(os.path.join(a.out, "soak_summary.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join("[soak] " + l for l in lines), flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
