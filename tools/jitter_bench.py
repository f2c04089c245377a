#!/usr/bin/env python3
"""Wake-latency benchmark: hapticd's servo loop against cyclictest, the OS floor.

For each rate, runs `cyclictest -m -p PRIO -i PERIOD_US -l N -h BUCKETS` (A) and
`hapticd run` on config/sim.yaml with loop.clock realtime at the same priority, period and
duration (B), alternating A B A B so drift hits both, and prints the wake latency p50 / p99 /
p99.9 / max of each and the ratio hapticd / cyclictest. hapticd's per-tick latencies come from
its own tick log (via `hapticd export`) and are put in cyclictest's 1 us buckets, so both
distributions are summarised the same way. Then it finds the highest loop.rate_hz at which
hapticd holds p99.9 wake latency under 20 % of the period with no overrun fault.

Needs root (SCHED_FIFO, mlockall) for numbers that mean anything; says so otherwise.
Usage: tools/jitter_bench.py [--rates 1000,2000,5000,10000] [--duration 10] [--rounds 2]
"""
import argparse
import csv
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def percentiles(hist, maximum):
    """p50/p99/p99.9 as the lower edge (us) of the bucket holding that rank, like cyclictest."""
    total = sum(hist.values())
    out = {}
    for name, q in (("p50", 0.5), ("p99", 0.99), ("p999", 0.999)):
        rank = max(1, math.ceil(q * total))
        seen = 0
        for us in sorted(hist):
            seen += hist[us]
            if seen >= rank:
                out[name] = us
                break
    out["max"] = maximum
    out["samples"] = total
    return out


def merge(into, hist):
    for k, v in hist.items():
        into[k] = into.get(k, 0) + v


def run_cyclictest(rate, duration, prio, buckets, cpu=None):
    period_us = round(1e6 / rate)
    loops = int(duration * rate)
    cmd = ["cyclictest", "-m", "-p", str(prio), "-i", str(period_us), "-l", str(loops),
           "-h", str(buckets), "-q"] + (["-a", str(cpu)] if cpu is not None else [])
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"cyclictest failed ({p.returncode}): {p.stderr.strip()}")
    hist, maximum, overflows = {}, 0, 0
    for line in p.stdout.splitlines():
        m = re.match(r"^(\d+)\s+(\d+)$", line)
        if m and int(m.group(2)) > 0:
            hist[int(m.group(1))] = int(m.group(2))
        elif line.startswith("# Max Latencies:"):
            maximum = int(line.split(":")[1].split()[0])
        elif line.startswith("# Histogram Overflows:"):
            overflows = int(line.split(":")[1].split()[0])
    if overflows:
        hist[buckets] = hist.get(buckets, 0) + overflows  # beyond the histogram: counted at its end
    return hist, maximum


def run_hapticd(binary, rate, duration, prio, workdir, cpu=None):
    log = os.path.join(workdir, "jitter.hlog")
    summary = os.path.join(workdir, "jitter.json")
    cmd = [binary, "run", "--duration", str(duration), "--log", log, "--summary-json", summary,
           "--set", "loop.clock=realtime", "--set", f"loop.rate_hz={rate}",
           "--set", f"loop.rt_priority={prio}"] + (["--set", f"loop.cpu={cpu}"] if cpu is not None else [])
    p = subprocess.run(cmd, capture_output=True, text=True)
    s = json.load(open(summary)) if os.path.exists(summary) else {}
    if p.returncode not in (0, 1) or not s:
        sys.exit(f"hapticd run failed ({p.returncode}): {p.stderr.strip()}")
    csv_path = os.path.join(workdir, "jitter.csv")
    subprocess.run([binary, "export", log, "--out", csv_path], check=True, capture_output=True)
    hist, maximum = {}, 0
    with open(csv_path) as f:
        for row in csv.DictReader(f):
            us = float(row["wake_latency_us"])
            hist[int(us)] = hist.get(int(us), 0) + 1
            maximum = max(maximum, int(us))
    os.remove(summary)
    return hist, maximum, s


def fmt(p):
    return f"{p['p50']:>5} {p['p99']:>5} {p['p999']:>6} {p['max']:>6}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hapticd", default=os.path.join(ROOT, "build/service/hapticd"))
    ap.add_argument("--rates", default="1000,2000,5000,10000")
    ap.add_argument("--duration", type=float, default=10.0, help="seconds per run")
    ap.add_argument("--rounds", type=int, default=2, help="A B pairs per rate")
    ap.add_argument("--priority", type=int, default=80)
    ap.add_argument("--buckets", type=int, default=2000, help="cyclictest histogram size (us)")
    ap.add_argument("--max-rate-duration", type=float, default=None,
                    help="seconds per run of the highest-rate search (default: --duration)")
    ap.add_argument("--cpu", type=int, default=None,
                    help="pin both: cyclictest -a CPU and hapticd loop.cpu=CPU (default: not pinned)")
    ap.add_argument("--json", help="also write all results here")
    args = ap.parse_args()

    if os.geteuid() != 0:
        print("warning: not root: SCHED_FIFO and mlockall will be refused; the numbers below are "
              "not real-time numbers", file=sys.stderr)
    rates = [int(r) for r in args.rates.split(",")]
    uname = platform.uname()
    print(f"machine: {uname.node} {uname.release} {uname.machine}, {os.cpu_count()} CPUs; "
          f"priority {args.priority}, {args.duration} s per run, {args.rounds} A/B rounds, "
          f"{'pinned to CPU ' + str(args.cpu) if args.cpu is not None else 'not pinned'}")
    results = {"rates": {}, "machine": f"{uname.release} {uname.machine} {os.cpu_count()} CPUs"}
    # The tick log goes to tmpfs when there is one: disk writeback is not what is measured.
    shm = "/dev/shm" if os.path.isdir("/dev/shm") else None
    with tempfile.TemporaryDirectory(dir=shm) as work:
        print(f"{'rate':>6} | {'cyclictest  p50   p99  p99.9    max':>35} | "
              f"{'hapticd  p50   p99  p99.9    max':>32} | ratio p99.9  p99 | rt")
        for rate in rates:
            ct_hist, ct_max, hd_hist, hd_max, rt = {}, 0, {}, 0, None
            for _ in range(args.rounds):
                h, m = run_cyclictest(rate, args.duration, args.priority, args.buckets, args.cpu)
                merge(ct_hist, h)
                ct_max = max(ct_max, m)
                h, m, s = run_hapticd(args.hapticd, rate, args.duration, args.priority, work, args.cpu)
                merge(hd_hist, h)
                hd_max = max(hd_max, m)
                rt = s["rt"]
            ct, hd = percentiles(ct_hist, ct_max), percentiles(hd_hist, hd_max)
            ratio = hd["p999"] / ct["p999"] if ct["p999"] else float("inf")
            ratio99 = hd["p99"] / ct["p99"] if ct["p99"] else float("inf")
            rt_text = ("FIFO" if rt["sched_fifo"] else "OTHER") + ("+mlock" if rt["memory_locked"] else "")
            print(f"{rate:>6} | {'':>11}{fmt(ct)} | {'':>8}{fmt(hd)} | {ratio:>11.2f} {ratio99:>4.2f} | {rt_text}")
            results["rates"][rate] = {"cyclictest_us": ct, "hapticd_us": hd,
                                      "ratio_p999": ratio, "ratio_p99": ratio99, "rt": rt}

        # Highest sustainable rate: p99.9 wake latency < 20 % of the period (and, for hapticd,
        # no overrun fault). cyclictest on the same criterion is what the machine allows.
        dur = args.max_rate_duration or args.duration

        def sustains(tool, rate):
            if tool == "hapticd":
                h, m, s = run_hapticd(args.hapticd, rate, dur, args.priority, work, args.cpu)
                faults = len(s["faults"])
            else:
                h, m = run_cyclictest(rate, dur, args.priority, args.buckets, args.cpu)
                faults = 0
            p = percentiles(h, m)
            ok = faults == 0 and p["p999"] < 0.2 * 1e6 / rate
            print(f"  {tool:>10} {rate:>6} Hz: p99.9 {p['p999']} us vs budget {0.2e6 / rate:.1f} us, "
                  f"faults {faults} -> {'holds' if ok else 'does not hold'}")
            return ok

        def highest(tool):
            best, worst = None, None
            for r in [1000, 2000, 5000, 10000, 20000, 50000, 100000]:
                if sustains(tool, r):
                    best = r
                else:
                    worst = r
                    break
            if best is not None and worst is not None:
                while worst - best > max(50, best // 20):
                    mid = (best + worst) // 2
                    if sustains(tool, mid):
                        best = mid
                    else:
                        worst = mid
            return best, worst

        print("highest sustainable rate (p99.9 wake latency < 20 % of the period, no fault):")
        results["highest_sustainable_rate_hz"] = {}
        for tool in ("cyclictest", "hapticd"):
            best, worst = highest(tool)
            results["highest_sustainable_rate_hz"][tool] = best
            print(f"  -> {tool}: {best if best else 'none'} Hz" + (f" (fails at {worst} Hz)" if worst else ""))
    if args.json:
        json.dump(results, open(args.json, "w"), indent=2)


if __name__ == "__main__":
    main()
