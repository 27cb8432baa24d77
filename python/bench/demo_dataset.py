"""A demonstration file into manibench.demos.TransitionDataset and one epoch
of batches, beside h5py reading the same arrays directly.

    PYTHONPATH=build/python python3 python/bench/demo_dataset.py drawer.h5 [--fields transition]

Each round times, alternately: (a) h5py reading, per trajectory, the
arrays the Dataset holds (obs and actions; with --fields transition also
rewards and terminated), as a user would without manibench.demos; (b) the
Dataset made from the file and one epoch of shuffled batches of
--batch-size through its loader(). The file is read once before, so both
read it from the page cache. Prints each round and the medians.
"""
import argparse
import statistics
import time

import h5py
import torch

from manibench import demos

KEYS = {"bc": ("obs", "actions"), "transition": ("obs", "actions", "rewards", "terminated")}


def read_directly(path, keys):
    with h5py.File(path, "r") as f:
        names = [n for n in f if n.startswith("traj_")]
        return {n: {k: f[n][k][()] for k in keys} for n in names}


def dataset_epoch(path, fields, batch_size):
    data = demos.TransitionDataset(path, fields=fields)
    batches = 0
    for batch in data.loader(batch_size=batch_size, shuffle=True,
                             generator=torch.Generator().manual_seed(0)):
        batches += 1
    return len(data), batches


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file")
    parser.add_argument("--fields", choices=sorted(KEYS), default="bc")
    parser.add_argument("--batch-size", type=int, default=256)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    arrays = read_directly(args.file, KEYS[args.fields])  # into the page cache
    steps = sum(len(a["actions"]) for a in arrays.values())
    print(f"{args.file}: {len(arrays)} trajectories, {steps} steps, fields {args.fields}, "
          f"batches of {args.batch_size}")
    direct, dataset = [], []
    for r in range(args.rounds):
        start = time.perf_counter()
        read_directly(args.file, KEYS[args.fields])
        direct.append(time.perf_counter() - start)
        start = time.perf_counter()
        items, batches = dataset_epoch(args.file, args.fields, args.batch_size)
        dataset.append(time.perf_counter() - start)
        print(f"round {r}: h5py direct {direct[-1]:.3f} s, Dataset + epoch ({items} steps, "
              f"{batches} batches) {dataset[-1]:.3f} s")
    print(f"median: h5py direct {statistics.median(direct):.3f} s, Dataset + epoch "
          f"{statistics.median(dataset):.3f} s")


if __name__ == "__main__":
    main()
