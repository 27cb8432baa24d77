"""Environment steps per second from Python, to set beside `manibench bench`.

    PYTHONPATH=build/python python3 python/bench/step_rate.py Reach-v0 --steps 2000
    build/bin/manibench bench Reach-v0 --steps 2000

As `manibench bench` does: episodes on the split's objects in turn with
seeds 0, 1, ..., until --steps env steps ran; only env.step() is timed
(resets apart), with uniform random actions made in numpy beforehand
(--policy zero: zero actions, the trajectories of `manibench bench
--policy zero`, for comparing the work per step exactly).
--num-envs N times make_vec(N) instead (steps of all environments counted;
auto-resets included in the timing, as a vector user sees them).
"""
import argparse
import time

import numpy as np

import manibench


def single(args):
    env = manibench.make(args.task, obs_mode=args.obs, controller=args.controller,
                         dtypes=args.dtypes)
    objects = env.list_objects("train")
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, size=(args.steps, env.action_space.shape[0]))
    if args.policy == "zero":
        actions[:] = 0
    steps, episodes, step_time, reset_time = 0, 0, 0.0, 0.0
    while steps < args.steps:
        start = time.perf_counter()
        env.reset(seed=episodes, options={"object_id": objects[episodes % len(objects)]})
        reset_time += time.perf_counter() - start
        episodes += 1
        done = False
        while not done and steps < args.steps:
            start = time.perf_counter()
            _, _, terminated, truncated, _ = env.step(actions[steps])
            step_time += time.perf_counter() - start
            steps += 1
            done = terminated or truncated
    env.close()
    print(f"{args.task} ({args.obs}), Python env.step: {steps} steps in {step_time:.3f} s: "
          f"{steps / step_time:.1f} steps/s ({episodes} episodes, resets {reset_time:.3f} s)")


def vector(args):
    venv = manibench.make_vec(args.task, num_envs=args.num_envs, spin_wait=args.spin_wait,
                              obs_mode=args.obs, controller=args.controller, dtypes=args.dtypes)
    rng = np.random.default_rng(0)
    venv.reset(seed=0)
    batches = max(1, args.steps // args.num_envs)
    actions = rng.uniform(-1, 1, size=(batches,) + venv.action_space.shape)
    start = time.perf_counter()
    for t in range(batches):
        venv.step(actions[t])
    elapsed = time.perf_counter() - start
    venv.close()
    steps = batches * args.num_envs
    print(f"{args.task} ({args.obs}), make_vec({args.num_envs}): {steps} steps in {elapsed:.3f} s: "
          f"{steps / elapsed:.1f} steps/s")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("task")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--obs", default="state")
    parser.add_argument("--controller", default=None)
    parser.add_argument("--policy", choices=["random", "zero"], default="random")
    parser.add_argument("--dtypes", choices=["compact", "cpp"], default="compact",
                        help="make()'s dtypes (cpp: float64 vectors, float rgb)")
    parser.add_argument("--num-envs", type=int, default=0, help="time make_vec(N) (0: one env)")
    parser.add_argument("--spin-wait", type=float, default=None,
                        help="make_vec's spin_wait in seconds (default: make_vec's)")
    args = parser.parse_args()
    (vector if args.num_envs else single)(args)


if __name__ == "__main__":
    main()
