#!/usr/bin/python3
# tools/hapticd-plot, each of its three plots from one command, against the hapticd under test:
# every picture must be written as PNG and SVG and hold something (not an empty canvas), and a
# bad input must be refused with exit 2. Run by ctest; fails, never skips, without matplotlib.
import os
import subprocess
import sys
import tempfile

source, binary = sys.argv[1], sys.argv[2]
tool = os.path.join(source, "tools", "hapticd-plot")
env = dict(os.environ, HAPTICD_BINARY=binary)
failures = []


def check(args, prefix, min_png=20000):
    r = subprocess.run([tool] + args + ["--out", prefix], env=env, capture_output=True,
                       text=True)
    if r.returncode != 0:
        failures.append("%s: exit %d\n%s" % (" ".join(args), r.returncode, r.stderr))
        return
    for ext in ("png", "svg"):
        path = prefix + "." + ext
        if path not in r.stdout.split():
            failures.append("%s: did not print %s" % (" ".join(args), path))
        if not os.path.exists(path):
            failures.append("%s: wrote no %s" % (" ".join(args), path))
            continue
        with open(path, "rb") as f:
            data = f.read()
        if ext == "png" and (not data.startswith(b"\x89PNG") or len(data) < min_png):
            failures.append("%s: %s is not a PNG of substance (%d bytes)" % (args, path, len(data)))
        if ext == "svg" and b"<svg" not in data:
            failures.append("%s: %s is not an SVG" % (args, path))


with tempfile.TemporaryDirectory() as tmp:
    check(["zwidth"], os.path.join(tmp, "zwidth"))
    check(["nyquist"], os.path.join(tmp, "nyquist"))
    check(["nyquist", "--config", os.path.join(source, "config", "coupling-example.yaml")],
          os.path.join(tmp, "nyquist-coupled"), min_png=5000)
    check(["coupling", "--config", os.path.join(source, "config", "coupling-example.yaml")],
          os.path.join(tmp, "coupling"))
    check(["log"], os.path.join(tmp, "log"))
    log = os.path.join(tmp, "free.hlog")
    subprocess.run([binary, "run", "--duration", "1", "--set", "loop.clock=freerun", "--log", log],
                   check=True, capture_output=True)
    check(["log", log], os.path.join(tmp, "log-freerun"))
    # A device of several joints: the log over time, and the workspace with its trajectory.
    delta = os.path.join(tmp, "delta.hlog")
    subprocess.run([binary, "run", "--config", os.path.join(source, "config", "sim-delta.yaml"),
                    "--duration", "2", "--log", delta], check=True, capture_output=True)
    check(["log", delta], os.path.join(tmp, "log-delta"))
    for ext in ("png", "svg"):
        if not os.path.exists(os.path.join(tmp, "log-delta-workspace." + ext)):
            failures.append("a delta's log: no workspace figure (%s)" % ext)
    r = subprocess.run([tool, "log", os.path.join(tmp, "missing.hlog")], env=env,
                       capture_output=True, text=True)
    if r.returncode != 2 or "no such file" not in r.stderr:
        failures.append("a missing log: exit %d, %s" % (r.returncode, r.stderr))
    not_a_log = os.path.join(tmp, "x.hlog")
    with open(not_a_log, "w") as f:
        f.write("position,force\n")
    r = subprocess.run([tool, "log", not_a_log], env=env, capture_output=True, text=True)
    if r.returncode != 2 or "not a hapticd tick log" not in r.stderr:
        failures.append("not a log: exit %d, %s" % (r.returncode, r.stderr))

for f in failures:
    print("FAILED: " + f)
sys.exit(1 if failures else 0)
