"""A policy for the evaluation kit, in Python (ManiSkill's UserPolicy form):

    build/bin/manibench eval Reach-v0 --policy examples/python/random_policy.py --workers 2

The kit runs it in each worker through the `python` policy plugin's
embedded interpreter; obs is what manibench.make returns in the evaluated
observation mode (a vector, or a dict of arrays).
"""
import numpy as np


class UserPolicy:
    def __init__(self, info):
        # info: task, obs_mode, observation_dim, action_dim, and the segments
        self.action_dim = info["action_dim"]
        self.rng = np.random.default_rng(0)

    def reset(self, seed):
        self.rng = np.random.default_rng(seed)

    def act(self, obs):
        return self.rng.uniform(-1.0, 1.0, self.action_dim)
