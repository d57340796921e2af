import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
import meshes  # noqa: E402


@pytest.fixture(params=[2, 3], ids=["2d", "3d"])
def dim(request):
    return request.param


@pytest.fixture
def mesh(dim):
    return meshes.jittered(dim)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
