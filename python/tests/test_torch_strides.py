"""mbi.torch with the tensors PyTorch makes: the zero-stride gradients of loss.sum() and
loss.mean(), expand()ed poses (a zero stride in X), t()ed (column-major) poses and gradients,
each checked against central finite differences of the same loss (exact up to round-off: the
positions are linear in X)."""
import numpy as np
import pytest

import mbi
import meshes

torch = pytest.importorskip("torch")
import mbi.torch as mt  # noqa: E402

METHODS = ["bi", "modified-bi", "phong"]


@pytest.fixture(scope="module", params=METHODS)
def deformer(request):
    U, T = meshes.jittered(3)
    return mbi.Deformer(U, T, meshes.points(U, 40), method=request.param)


def finite_differences(loss, X, h=1e-3):
    """d loss / dX by central differences, X a float64 numpy array of any shape."""
    grad = np.zeros_like(X)
    for index in np.ndindex(X.shape):
        E = np.zeros_like(X)
        E[index] = h
        grad[index] = (loss(X + E) - loss(X - E)) / (2 * h)
    return grad


def close(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.abs(a - b).max() <= 1e-8 * (1 + np.abs(b).max())


def pose(deformer):
    """A pose of the deformer's control mesh (meshes.jittered(3))."""
    return meshes.pose(meshes.jittered(3)[0])


def test_sum_backward(deformer):
    X = torch.tensor(pose(deformer), requires_grad=True)
    mt.deform(deformer, X).sum().backward()  # the gradient handed to vjp has strides (0, 0)
    assert torch.isfinite(X.grad).all()
    fd = finite_differences(lambda Y: deformer.deform(Y).sum(), pose(deformer))
    assert close(X.grad.numpy(), fd)


def test_mean_backward(deformer):
    X = torch.tensor(pose(deformer), requires_grad=True)
    mt.deform(deformer, X).mean().backward()
    fd = finite_differences(lambda Y: deformer.deform(Y).mean(), pose(deformer))
    assert close(X.grad.numpy(), fd)


def test_batch_sum_and_mean_backward(deformer):
    base = np.stack([pose(deformer), pose(deformer) * 1.1])
    for reduce in (torch.sum, torch.mean):
        X = torch.tensor(base, requires_grad=True)
        reduce(mt.deform(deformer, X)).backward()
        fd = finite_differences(lambda Y: float(reduce(torch.from_numpy(deformer.deform(Y)))), base)
        assert close(X.grad.numpy(), fd)


def test_expanded_pose(deformer):
    # one row for every vertex (stride 0), and a batch of one pose repeated (stride 0 on frames)
    row = torch.tensor([0.2, -0.1, 0.4], dtype=torch.float64, requires_grad=True)
    n = deformer.vertices
    W = torch.from_numpy(np.random.default_rng(5).standard_normal((deformer.points, 3)))
    (mt.deform(deformer, row.expand(n, 3)) * W).sum().backward()
    fd = finite_differences(lambda r: float((deformer.deform(np.tile(r, (n, 1))) * W.numpy()).sum()), row.detach().numpy())
    assert close(row.grad.numpy(), fd)
    X = torch.tensor(pose(deformer), requires_grad=True)
    (mt.deform(deformer, X.expand(3, n, 3)) ** 2).mean().backward()
    fd = finite_differences(lambda Y: float((np.stack([deformer.deform(Y)] * 3) ** 2).mean()), pose(deformer))
    assert close(X.grad.numpy(), fd)


def test_transposed_pose_and_gradient(deformer):
    Xt = torch.tensor(pose(deformer).T.copy(), requires_grad=True)  # (3, n); Xt.t() is column-major
    target = torch.from_numpy(meshes.points(meshes.jittered(3)[0], deformer.points, seed=9))
    positions = mt.deform(deformer, Xt.t())
    # positions.t(): the gradient reaching vjp is the transpose of a contiguous one
    ((positions.t() - target.t()) ** 2).sum().backward()
    fd = finite_differences(lambda Y: float(((deformer.deform(Y.T) - target.numpy()) ** 2).sum()), Xt.detach().numpy())
    assert close(Xt.grad.numpy(), fd)


def test_float32_expanded_gradient(deformer):
    X = torch.tensor(pose(deformer), dtype=torch.float32, requires_grad=True)
    mt.deform(deformer, X).sum().backward()
    assert X.grad.dtype == torch.float32
    expect = deformer.vjp(np.ones((deformer.points, 3)))
    assert np.abs(X.grad.numpy() - expect).max() < 1e-4 * (1 + np.abs(expect).max())
