"""A flip map filled into one Zarr store by a dask.distributed cluster, tile by tile.

Each task fills its part of the store (`flip_map(store=..., tile=(i, n))`: whole chunks,
band by band, so no worker holds more than a band of the map: the map may be larger than
any worker's memory); the same store the Slurm and Kubernetes examples fill with `--tile`.
The store is then checked equal, bit for bit, to the map made in one process (skip that with
--no-check for a map too large for memory).

    python examples/dask_map.py --size 2048 --t-max 20 --tiles 8 --workers 2 out/dask.zarr
"""

import argparse
import shutil
import sys
import time

import numpy as np
from dask.distributed import Client, LocalCluster

import chaoscope


def fill(store: str, size: int, t_max: float, tile: tuple) -> dict:
    """One task: part `tile` of the store (returns what it filled)."""
    opened = chaoscope.flip_map(size=size, t_max=t_max, store=store, tile=tile, progress=False)
    return opened.attrs["filled"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("store", help="the Zarr store to fill (MAP.zarr; replaced)")
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--t-max", type=float, default=20.0)
    parser.add_argument("--tiles", type=int, default=8, help="tasks the map is split into")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument("--no-check", action="store_true", help="skip the single-process map")
    args = parser.parse_args(argv)
    shutil.rmtree(args.store, ignore_errors=True)
    started = time.monotonic()
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True) as cluster:
        with Client(cluster) as client:
            tasks = [
                client.submit(fill, args.store, args.size, args.t_max, (i, args.tiles), pure=False)
                for i in range(args.tiles)
            ]
            filled = client.gather(tasks)
    pixels = sum(f["pixels"] for f in filled)
    print(f"{args.tiles} tasks on {args.workers} workers filled {pixels} pixels "
          f"in {time.monotonic() - started:.1f} s -> {args.store}")
    store = chaoscope.open_store(args.store)
    if args.no_check:
        return 0
    whole = chaoscope.flip_map(size=args.size, t_max=args.t_max, progress=False)
    same = store["map"].values.tobytes() == whole.values.tobytes()
    print("equal to the single-process map, bit for bit" if same else "DIFFERS from the single-process map")
    return 0 if same and np.isfinite(whole.values).any() else 1


if __name__ == "__main__":
    sys.exit(main())
