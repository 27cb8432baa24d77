"""A random agent on one episode: manibench from Python in a few lines.

    PYTHONPATH=build/python python3 examples/python/random_agent.py OpenCabinetDrawer-v0
"""
import sys

import manibench

task = sys.argv[1] if len(sys.argv) > 1 else "Reach-v0"
env = manibench.make(task, obs_mode="pointcloud")
print(env.observation_space)
print(env.action_space)
obs, info = env.reset(seed=0)
total, done = 0.0, False
while not done:
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    total += reward
    done = terminated or truncated
print(f"object {info['object_id']}: {info['elapsed_steps']} steps, return {total:.3f}, "
      f"success conditions {info['eval_info']}")
env.close()
