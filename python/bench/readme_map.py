"""The README's flip map from Python beside the command line: time and memory, side by side.

Interleaved repetitions of the same job, the command line's
    chaoscope flip --size N --t-max T --output PNG --data NPY
(wall time of the process) and, in a fresh Python process, flip_map + picture + np.save
(wall time of those calls, the imports not counted), medians reported with their ratio; the
Python process's peak RSS over its baseline after the imports, against the map's bytes and
the command line's own peak RSS. Prints one JSON line.

    target/pyenv/bin/python python/bench/readme_map.py --size 1024 --t-max 30 --repeat 3
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHILD = r"""
import json, resource, sys, time
import numpy as np
import chaoscope
size, t_max, png, npy = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], sys.argv[4]
def rss_kib():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
base = rss_kib()
started = time.perf_counter()
flips = chaoscope.flip_map(size=size, t_max=t_max, progress=False)
mapped = time.perf_counter() - started
chaoscope.picture(flips).save(png)
np.save(npy, flips.values)
seconds = time.perf_counter() - started
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"seconds": seconds, "map_seconds": mapped, "base_kib": base, "peak_kib": peak,
                  "map_bytes": flips.values.nbytes, "place": flips.attrs["place"]}))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--t-max", type=float, default=30.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--binary", default="target/release/chaoscope",
                        help="the command line to compare with (cargo's binary)")
    args = parser.parse_args()
    binary = Path(args.binary)
    cli_times, py_times, py_runs, cli_peaks = [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeat):
            # Alternate which goes first: the machine's speed drifts within minutes.
            order = ["cli", "python"] if k % 2 == 0 else ["python", "cli"]
            for which in order:
                png, npy = f"{tmp}/{which}{k}.png", f"{tmp}/{which}{k}.npy"
                if which == "cli":
                    started = time.perf_counter()
                    child = subprocess.Popen([str(binary), "flip", "--size", str(args.size),
                                              "--t-max", str(args.t_max), "--output", png,
                                              "--data", npy],
                                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                    # This child's own peak RSS (KiB), not the largest of all children's.
                    _, status, usage = os.wait4(child.pid, 0)
                    cli_times.append(time.perf_counter() - started)
                    assert status == 0, status
                    cli_peaks.append(usage.ru_maxrss)
                else:
                    out = subprocess.run([sys.executable, "-c", CHILD, str(args.size),
                                          str(args.t_max), png, npy],
                                         check=True, capture_output=True, text=True)
                    run = json.loads(out.stdout.strip().splitlines()[-1])
                    py_runs.append(run)
                    py_times.append(run["seconds"])
        import numpy as np

        same = np.load(f"{tmp}/cli0.npy").tobytes() == np.load(f"{tmp}/python0.npy").tobytes()
    cli, py = statistics.median(cli_times), statistics.median(py_times)
    grown = statistics.median(r["peak_kib"] - r["base_kib"] for r in py_runs) * 1024
    print(json.dumps({
        "size": args.size, "t_max": args.t_max, "repeat": args.repeat,
        "place": py_runs[0]["place"],
        "cli_s": cli_times, "python_s": py_times,
        "median_cli_s": cli, "median_python_s": py, "python_over_cli": py / cli,
        "median_python_map_only_s": statistics.median(r["map_seconds"] for r in py_runs),
        "map_bytes": py_runs[0]["map_bytes"],
        "python_peak_over_baseline_bytes": grown,
        "python_peak_over_baseline_in_maps": grown / py_runs[0]["map_bytes"],
        "cli_peak_rss_bytes": statistics.median(cli_peaks) * 1024,
        "python_peak_rss_bytes": statistics.median(r["peak_kib"] for r in py_runs) * 1024,
        "npy_bit_equal": same,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
