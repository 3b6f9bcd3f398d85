"""DQN grasp agent (paper 3.1, eq. 4-11) for terminal one-step episodes.

**Network.** The evaluation network Q_eva (parameters theta) is trained and acts.

**TD target.** The paper's target is y = r + gamma max_{a'} Q_tar(s', a') (eq. 8, gamma = 0.5,
with a target network Q_tar). In vgs each grasp-and-assembly is one episode and the next
observation is a fresh, independently placed peg, so the action cannot influence s': every
transition is terminal and the target is

    y = r

(a contextual-bandit target). gamma and a target network could change no result, so the agent
has neither (``agent.gamma`` and ``agent.target_update_period`` were removed, CHANGELOG.md); a
transition that is not terminal (``done=False``) is refused.

**Loss.** With a = (k, i, j) the executed rotation and pixel, the Huber loss (eq. 11, smooth L1
with beta = 1)

    L(x) = 0.5 x^2 if |x| < 1 else |x| - 0.5,   x = y - Q_eva(s, a),

is applied only at pixel (i, j) of rotation k and of the opposite rotation k' = (k + R/2) mod R
(the two-finger gripper is symmetric; as VPG, for even R only), and summed over these one or two
terms; every other output pixel gets zero gradient. The parameters take one SGD step
(momentum, weight decay). Each update returns Delta Q = |y - Q_eva(s, a)| (eq. 10), measured
before the step.

**BatchNorm.** Actions and TD targets use eval mode (running statistics); the update's forward
pass uses train mode (batch statistics over the one or two rotated copies).

**Action spaces.** With ``network.action = "position"`` (the paper's) an action is a pixel
(i, j) of one Q map; the jaws close across the peg's axis as perceived in the same heightmap
(:func:`vgs.grasping.actions.perceived_jaw_angle`), a function of the map alone, so the
decision, the update and every replay turn the network's input (``rotate="input"``) by the same
angle. Its action is stored as (0, i, j) and its loss falls on that one pixel. With
``"rotation"`` (visual-pushing-grasping's) an action is (k, i, j) as above.

**Exploration.** Episodes e < N_random (``random_episodes``) act at random (epsilon = 1); after
that epsilon anneals linearly from epsilon_start to epsilon_end over the remaining episodes:

    epsilon(e) = eps_start + (eps_end - eps_start) * min(1, (e - N_random) / D),
    D = max(1, E - N_random - 1),

with E the total number of episodes. An exploratory action picks a uniformly random valid pixel
(and, for the rotation action, a uniformly random rotation); a greedy one the argmax of Q over
the maps and pixels, restricted to valid pixels.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from torch import Tensor

from vgs.config import AgentConfig, NetworkConfig, to_dict
from vgs.errors import ConfigError
from vgs.grasping.actions import perceived_jaw_angle
from vgs.grasping.dqn import DeltaQMonitor, epsilon_schedule, opposite_rotation, td_loss
from vgs.grasping.network import GraspQNetwork, rotation_angle
from vgs.grasping.preprocess import check_heightmaps, preprocess
from vgs.grasping.replay import ReplayBuffer, Transition


@dataclass(frozen=True)
class GraspAction:
    """A chosen grasp.

    Attributes:
        rotation: Rotation index k in [0, R) (rotation action); 0 for the position action.
        row: Pixel row i.
        col: Pixel column j.
        angle: Closing direction of the jaws in pixel axes [rad]: theta_k = 2 pi k / R
            (rotation action) or the perceived angle across the peg (position action).
        q_value: Q_eva(s, (k, i, j)) (NaN if the forward pass was skipped).
        explored: True if chosen at random (epsilon branch).
        q_map: The whole Q map (R, H, W) of the evaluation network in eval mode, or None if
            the forward pass was skipped (``skip_q_if_exploring``).
    """

    rotation: int
    row: int
    col: int
    angle: float
    q_value: float
    explored: bool
    q_map: np.ndarray | None = field(repr=False)

    @property
    def action(self) -> tuple[int, int, int]:
        """``(rotation, row, col)`` as stored in a :class:`Transition`."""
        return self.rotation, self.row, self.col










class GraspAgent:
    """The evaluation grasp Q network, SGD, Huber TD updates and epsilon-greedy actions.

    Heightmaps are passed raw, as the simulator gives them: ``color`` uint8 (H, W, 3) and
    ``depth`` float32 (H, W) [m]; the agent normalises them (:mod:`vgs.grasping.preprocess`).

    Args:
        network_cfg: Network configuration (backbone, R, weights, depth normalisation).
        agent_cfg: Learning rate, momentum, weight decay, exploration, replay.
        device: Torch device string (``"cpu"`` or ``"cuda"``).
        seed: Seed of the network initialisation (the global torch RNG is left untouched).
        rotate: Rotation mode of :class:`GraspQNetwork` (``"input"`` or ``"features"``);
            default: ``network_cfg.rotate``.
        channels_last: Channels-last memory format for the networks (default: on; 1.2-1.5x
            faster decisions on a 2-core CPU, see docs/grasping.md; same values up to rounding).

    Attributes:
        eva_net: Evaluation network Q_eva.
        optimizer: SGD on the evaluation network.
        updates: Number of gradient updates so far.
    """

    def __init__(
        self,
        network_cfg: NetworkConfig,
        agent_cfg: AgentConfig,
        device: str = "cpu",
        seed: int = 0,
        rotate: str | None = None,
        channels_last: bool = True,
    ) -> None:
        self.network_cfg = network_cfg
        self.agent_cfg = agent_cfg
        self.device = torch.device(device)
        self.rotate = network_cfg.rotate if rotate is None else rotate
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            net = GraspQNetwork(network_cfg, rotate=self.rotate, channels_last=channels_last)
        self.eva_net = net.to(self.device)
        self.optimizer = torch.optim.SGD(
            self.eva_net.parameters(),
            lr=agent_cfg.learning_rate,
            momentum=agent_cfg.momentum,
            weight_decay=agent_cfg.weight_decay,
        )
        self.updates = 0

    @property
    def num_rotations(self) -> int:
        """Q maps per heightmap: R (rotation action) or 1 (position action)."""
        return self.network_cfg.q_maps

    @property
    def position_action(self) -> bool:
        """Whether the action is the paper's position alone (``network.action``)."""
        return self.network_cfg.action == "position"

    def _turn(self, depth: np.ndarray) -> list[float] | None:
        """The position action's input turn, the perceived closing angle, for one map."""
        return [perceived_jaw_angle(depth)] if self.position_action else None

    def _inputs(self, color: np.ndarray, depth: np.ndarray) -> tuple[Tensor, Tensor]:
        c, d = preprocess(color, depth, self.network_cfg)
        return c.to(self.device), d.to(self.device)

    def _autocast(self) -> contextlib.AbstractContextManager[Any]:
        """``torch.autocast`` in bfloat16 when ``network.precision`` asks for it, else nothing."""
        if self.network_cfg.precision == "bfloat16":
            return torch.autocast(device_type=self.device.type, dtype=torch.bfloat16)
        return contextlib.nullcontext()

    def q_values(self, color: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """Q map (R, H, W), float32, of the evaluation network in eval mode, no gradients."""
        return self._q_map(color, depth, self._turn(depth))

    def _q_map(self, color: np.ndarray, depth: np.ndarray, turn: list[float] | None
               ) -> np.ndarray:
        """:meth:`q_values` with the input turn (:meth:`_turn`) already known."""
        net = self.eva_net
        c, d = self._inputs(color, depth)
        was_training = net.training
        net.eval()
        with torch.inference_mode(), self._autocast():
            q = net(c, d, angles=turn)[0].float().cpu().numpy()
        net.train(was_training)
        return q

    def epsilon(self, episode: int, total_episodes: int) -> float:
        """Exploration rate of ``episode`` out of ``total_episodes`` (module docstring)."""
        return epsilon_schedule(episode, total_episodes, self.agent_cfg)

    def act(
        self,
        color: np.ndarray,
        depth: np.ndarray,
        epsilon: float,
        valid_mask: np.ndarray | None,
        rng: np.random.Generator,
        *,
        skip_q_if_exploring: bool = False,
    ) -> GraspAction:
        """Epsilon-greedy grasp.

        With probability epsilon: a uniformly random valid pixel (and rotation, for the
        rotation action). Otherwise the argmax of Q_eva over its maps and pixels, restricted
        to pixels where ``valid_mask`` is True when the mask has any True pixel (an empty or
        absent mask allows every pixel).

        Args:
            color: RGB heightmap, uint8 (H, W, 3).
            depth: Height map [m], float32 (H, W).
            epsilon: Exploration probability in [0, 1].
            valid_mask: Boolean (H, W) of allowed pixels (for example :func:`peg_mask`), or None.
            rng: Random generator for the exploration draws.
            skip_q_if_exploring: Draw the exploration coin first and skip the forward pass
                when it says explore; the action then has ``q_value`` NaN and ``q_map`` None.
                Saves a full R-rotation forward pass per random grasp (the random phase).

        Raises:
            ConfigError: On an epsilon outside [0, 1] or a mask of the wrong shape.
        """
        if not 0.0 <= epsilon <= 1.0:
            raise ConfigError("agent.epsilon", f"must lie in [0, 1], got {epsilon!r}")
        check_heightmaps(color, depth)
        height, width = depth.shape
        explored = bool(rng.random() < epsilon)
        turn = self._turn(depth)  # the position action's perceived angle, read once
        q = None if explored and skip_q_if_exploring else self._q_map(color, depth, turn)
        if valid_mask is None:
            valid = np.ones((height, width), bool)
        else:
            valid = np.asarray(valid_mask, dtype=bool)
            if valid.shape != (height, width):
                raise ConfigError(
                    "agent.valid_mask", f"must be {(height, width)}, got {valid.shape}"
                )
            if not valid.any():
                valid = np.ones((height, width), bool)
        if explored:
            rows, cols = np.nonzero(valid)
            pick = int(rng.integers(rows.size))
            i, j = int(rows[pick]), int(cols[pick])
            k = 0 if self.position_action else int(rng.integers(self.num_rotations))
        else:
            masked = np.where(valid[None], q, -np.inf)
            k, i, j = (int(v) for v in np.unravel_index(int(np.argmax(masked)), masked.shape))
        angle = turn[0] if turn is not None else rotation_angle(k, self.num_rotations)
        return GraspAction(
            rotation=k, row=i, col=j, angle=angle,
            q_value=math.nan if q is None else float(q[k, i, j]), explored=explored, q_map=q,
        )

    def target_value(self, transition: Transition) -> float:
        """TD target of a terminal one-step transition: y = r (module docstring).

        Raises:
            ConfigError: If the transition is not terminal (``done=False``).
        """
        if not transition.done:
            raise ConfigError("transition.done", "the agent learns terminal one-step episodes "
                                                 "(target y = r); got done=False")
        return float(transition.reward)

    def update(self, transition: Transition) -> dict[str, float]:
        """One SGD step on one transition.

        Returns:
            ``loss`` (summed Huber loss before the step), ``delta_q`` = |y - Q_eva(s, a)|,
            ``q_eva`` = Q_eva(s, a) (train-mode forward before the step) and ``target`` = y.

        Raises:
            ConfigError: If the action's rotation is outside [0, R) or its pixel outside the map,
                or the transition is not terminal.
        """
        k, row, col = (int(v) for v in transition.action)
        rotation_angle(k, self.num_rotations)
        height, width = transition.depth.shape
        if not (0 <= row < height and 0 <= col < width):
            raise ConfigError("transition.action", f"pixel {(row, col)} outside the map")
        y = self.target_value(transition)
        opposite = None if self.position_action else opposite_rotation(k, self.num_rotations)
        rotations = [k] if opposite is None or opposite == k else [k, opposite]
        c, d = self._inputs(transition.color, transition.depth)
        self.eva_net.train()
        with self._autocast():
            q = self.eva_net(c, d, rotations=rotations, angles=self._turn(transition.depth))[0]
        q = q.float()  # the loss in float32 whatever the forward pass ran in
        loss = td_loss(q, range(len(rotations)), row, col, y)
        q_eva = float(q[0, row, col].detach())
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        self.optimizer.step()
        self.updates += 1
        return {"loss": float(loss.detach()), "delta_q": abs(y - q_eva), "q_eva": q_eva,
                "target": y}

    def replay_update(
        self,
        buffer: ReplayBuffer,
        rng: np.random.Generator,
        exclude_reward: float | None = None,
    ) -> list[dict[str, float]]:
        """``agent.replay_batch`` prioritised replays, each followed by a surprise update.

        Each replay draws a transition by surprise rank (:class:`ReplayBuffer`), recomputes its
        TD target, takes one :meth:`update` step and stores
        the new Delta Q as its surprise.

        Args:
            buffer: The replay buffer.
            rng: Random generator for the rank draws.
            exclude_reward: Optionally replay only transitions whose reward differs from this
                value (VPG replays the opposite outcome of the latest grasp).

        Returns:
            One :meth:`update` dict per replay, with the slot as ``index``; empty if the buffer
            holds no candidate.
        """
        results: list[dict[str, float]] = []
        for _ in range(self.agent_cfg.replay_batch):
            drawn = buffer.sample(rng, exclude_reward)
            if drawn is None:
                break
            index, transition = drawn
            stats = self.update(transition)
            buffer.update_surprise(index, stats["delta_q"])
            results.append({**stats, "index": float(index)})
        return results

    def state_dict(self) -> dict[str, Any]:
        """The network, the optimiser, the update counter and the configuration."""
        return {
            "eva_net": self.eva_net.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "updates": self.updates,
            "network_cfg": to_dict(self.network_cfg),
            "rotate": self.rotate,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict`. A ``target_net`` entry (written before the target
        network was removed) is ignored.

        Raises:
            ConfigError: ``agent.checkpoint`` on missing entries or a different architecture.
        """
        missing = {"eva_net", "optimizer", "updates"} - set(state)
        if missing:
            raise ConfigError("agent.checkpoint", f"missing entries {sorted(missing)}")
        if state.get("rotate", self.rotate) != self.rotate:
            raise ConfigError("agent.checkpoint", f"saved with rotate={state['rotate']!r}")
        saved = state.get("network_cfg")
        mine = to_dict(self.network_cfg)
        if saved is not None and (saved.get("action", "rotation") != mine["action"] or any(
                saved.get(k) != mine[k] for k in ("backbone", "num_rotations"))):
            raise ConfigError(
                "agent.checkpoint",
                f"saved for {saved.get('backbone')} with the {saved.get('action', 'rotation')} "
                f"action and R={saved.get('num_rotations')}, this agent is "
                f"{mine['backbone']} with the {mine['action']} action and "
                f"R={mine['num_rotations']}",
            )
        try:
            self.eva_net.load_state_dict(state["eva_net"])
        except RuntimeError as exc:
            raise ConfigError("agent.checkpoint", str(exc)) from exc
        self.optimizer.load_state_dict(state["optimizer"])
        self.updates = int(state["updates"])


__all__ = [
    "DeltaQMonitor",
    "GraspAction",
    "GraspAgent",
    "epsilon_schedule",
    "opposite_rotation",
    "td_loss",
]
