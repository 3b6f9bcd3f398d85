"""Shared settings of the grasping tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import torch


@pytest.fixture(autouse=True)
def single_torch_thread() -> Iterator[None]:
    """Run each grasping test on one intra-op thread, restoring the previous count afterwards.

    The tensors here are tiny (light backbone on 32-64 px maps, DenseNet-121 on 64 px), so a
    second thread gains little, while on a shared 2-core machine OpenMP threads that wait for
    a busy core slow the updates down many times over.
    """
    previous = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(previous)
