import numpy as np
import pytest

import pacs

FAR = np.array([3.0, 0.0, 0.0])


@pytest.fixture
def demo():
    return pacs.Demo("sorting", seed=1)


def far_human(demo):
    """The sorting task's person moved 3 m away (keypoints, m)."""
    k = demo.keypoints(0.0)
    return k - k.mean(axis=0) + FAR + np.array([0.0, 0.0, 1.0])


def away(demo, period=0.01):
    """A camera (every `period` s) seeing the person 3 m away."""
    k = far_human(demo)

    def measure(t):
        return (t, k) if round(t / 0.001) % round(period / 0.001) == 0 else None

    return measure


def run(shield, steps, t0=0.0, dt=0.001, measure=None):
    """Step `steps` times; returns the commands."""
    out = []
    for k in range(steps):
        t = t0 + k * dt
        if measure is not None:
            m = measure(t)
            if m is not None:
                shield.measure(*m)
        out.append(shield.step(t))
    return out
