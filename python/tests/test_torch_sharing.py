"""mbi.torch shares memory with numpy where dtype and layout match: a float64 CPU tensor reaches
Deformer.deform and Deformer.vjp as a numpy view of its memory, their results come back as tensors
over the arrays mbi wrote, and a float64 numpy X is taken without a copy. Other dtypes are copied
(and the result converted back)."""
import numpy as np
import pytest

import mbi
import meshes

torch = pytest.importorskip("torch")
import mbi.torch as mt  # noqa: E402


class Spy:
    """A Deformer that records the arrays each deform and vjp call receives and returns."""

    def __init__(self, deformer):
        self.deformer, self.seen, self.made = deformer, [], []

    def _record(self, f, a):
        self.seen.append(a)
        self.made.append(f(a))
        return self.made[-1]

    def deform(self, X):
        return self._record(self.deformer.deform, X)

    def vjp(self, G):
        return self._record(self.deformer.vjp, G)


@pytest.fixture
def spy():
    U, T = meshes.jittered(3)
    return Spy(mbi.Deformer(U, T, meshes.points(U, 60, margin=0), method="modified-bi")), U


def test_float64_tensors_are_shared_both_ways(spy):
    spy, U = spy
    X = torch.tensor(meshes.pose(U), requires_grad=True)
    positions = mt.deform(spy, X)
    assert np.shares_memory(spy.seen[0], X.detach().numpy())  # X read where it is
    assert positions.data_ptr() == spy.made[0].ctypes.data  # the result is the array mbi wrote
    G = torch.randn(positions.shape, dtype=torch.float64)
    positions.backward(G)
    assert np.shares_memory(spy.seen[1], G.numpy())  # the incoming gradient read where it is
    assert X.grad is not None and np.array_equal(X.grad.numpy(), spy.made[1])


def test_float64_numpy_input_is_not_copied(spy):
    spy, U = spy
    X = meshes.pose(U)
    mt.deform(spy, X)
    assert np.shares_memory(spy.seen[0], X)


def test_second_order_results_are_shared(spy):
    spy, U = spy
    X = torch.tensor(meshes.pose(U), requires_grad=True)
    (g,) = torch.autograd.grad((mt.deform(spy, X) ** 2).sum(), X, create_graph=True)
    assert g.data_ptr() == spy.made[1].ctypes.data  # vjp's array, as the gradient
    V = torch.randn(X.shape, dtype=torch.float64)
    torch.autograd.grad(g, X, grad_outputs=V)
    assert any(np.shares_memory(a, V.numpy()) for a in spy.seen[2:])  # V reached deform in place


def test_other_dtypes_are_copied_and_converted_back(spy):
    spy, U = spy
    X = torch.tensor(meshes.pose(U), dtype=torch.float32, requires_grad=True)
    positions = mt.deform(spy, X)
    assert spy.seen[0].dtype == np.float64 and not np.shares_memory(spy.seen[0], X.detach().numpy())
    assert positions.dtype == torch.float32
