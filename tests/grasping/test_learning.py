"""End-to-end learning on a toy task with a known answer (see toy_task.py).

The first test fails if learning is broken: with the optimiser's rate at 0 or with the reward
paid for the other half, the same check does not hold (the control below runs the flipped case;
rate 0 was checked by hand, see docs/grasping.md).
"""

from __future__ import annotations

from .toy_task import learned, score, train_toy


def test_greedy_policy_learns_the_paying_half() -> None:
    agent, rng = train_toy()
    s = score(agent, rng)
    assert learned(s), s
    assert agent.updates == 400


def test_flipped_reward_is_not_mistaken_for_learning() -> None:
    agent, rng = train_toy(flip=True)
    s = score(agent, rng)
    assert not learned(s), s
    assert s.hits <= 2, s  # it learned the other half instead


def test_bfloat16_forward_passes_learn_too() -> None:
    """``network.precision = bfloat16`` (autocast forward passes, float32 weights and loss)
    learns the toy task as float32 does."""
    agent, rng = train_toy(precision="bfloat16")
    s = score(agent, rng)
    assert learned(s), s
