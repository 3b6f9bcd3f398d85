"""Typed, frozen configuration of every component, nested into one :class:`ExperimentConfig`.

Units are SI throughout (metres, kilograms, seconds, newtons, radians) unless a field name says
otherwise (``*_mm``, ``*_deg``). Every dataclass validates itself in ``__post_init__`` and raises
:class:`vgs.errors.ConfigError` naming the offending field, so bad input never reaches the physics.

Named profiles (:data:`PROFILES`): ``smoke`` (seconds, for tests), ``quick`` (minutes on a 2-core
CPU), ``medium`` (1.5-2 hours there) and ``paper`` (the paper's budget: 5000 training grasps,
1000 test assemblies).

The package's modules follow what they configure: :mod:`vgs.config.cell` (peg, hole, gripper,
force-torque sensor, camera, simulation), :mod:`vgs.config.control` (controller, assembly),
:mod:`vgs.config.learning` (network, agent, reward, training), :mod:`vgs.config.conditions`
(the test conditions, evaluation settings and test scenes), :mod:`vgs.config.experiment`
(reproduction, :class:`ExperimentConfig`, the profiles), :mod:`vgs.config.tree`
(``override``, ``to_dict``, ``from_dict``, ``same_config``, ``without_retired``) and
:mod:`vgs.config.configfile` (``read_config_file``: ``--config FILE``). Import the
names from :mod:`vgs.config` itself.
"""

from vgs.config.cell import (
    CameraConfig,
    CellConfig,
    FTSensorConfig,
    GripperConfig,
    HoleConfig,
    PegConfig,
    SimConfig,
)
from vgs.config.conditions import (
    COM_CONDITIONS,
    CONDITIONS,
    PAPER_CONDITIONS,
    EvalConfig,
    EvalScene,
    condition_peg,
    eval_scenes,
)
from vgs.config.configfile import read_config_file
from vgs.config.control import AssemblyConfig, ControllerConfig
from vgs.config.experiment import (
    PROFILES,
    REFERENCE_POLICIES,
    ExperimentConfig,
    ReproduceConfig,
    profile,
)
from vgs.config.learning import (
    ACTIONS,
    BACKBONES,
    PRECISIONS,
    ROTATE_MODES,
    AgentConfig,
    NetworkConfig,
    RewardConfig,
    TrainConfig,
)
from vgs.config.tree import (
    NO_SUCH_FIELD,
    from_dict,
    override,
    same_config,
    to_dict,
    without_retired,
)

__all__ = [
    "ACTIONS", "BACKBONES", "COM_CONDITIONS", "CONDITIONS", "PAPER_CONDITIONS", "NO_SUCH_FIELD",
    "PRECISIONS", "PROFILES", "REFERENCE_POLICIES",
    "ROTATE_MODES", "AgentConfig", "AssemblyConfig", "CameraConfig", "CellConfig",
    "ControllerConfig", "EvalConfig", "EvalScene", "ExperimentConfig", "FTSensorConfig",
    "GripperConfig", "HoleConfig", "NetworkConfig", "PegConfig", "ReproduceConfig", "RewardConfig",
    "SimConfig", "TrainConfig", "condition_peg", "eval_scenes", "from_dict", "override", "profile",
    "read_config_file", "same_config", "to_dict", "without_retired",
]
