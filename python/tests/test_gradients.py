"""Deformer.vjp (the exact adjoint of the linear map X -> positions) against finite differences,
and through PyTorch: torch.autograd.gradcheck and gradgradcheck in double for BI, Phong and
modified-BI, 2D and 3D, and a Hessian-vector product against the Hessian of a quadratic loss."""
import numpy as np
import pytest

import mbi
import meshes

METHODS = ["bi", "modified-bi", "phong"]


@pytest.mark.parametrize("method", METHODS)
def test_vjp_against_finite_differences(mesh, method):
    U, T = mesh
    d = U.shape[1]
    deformer = mbi.Deformer(U, T, meshes.points(U, 200), method=method)
    X = meshes.pose(U)
    G = np.random.default_rng(7).standard_normal((200, d))
    dX = deformer.vjp(G)
    assert dX.shape == (len(U), d)

    def loss(Y):
        return float((G * deformer.deform(Y)).sum())

    h = 1e-3  # L is linear in X: central differences are exact up to round-off
    fd = np.zeros_like(X)
    for i in range(len(U)):
        for c in range(d):
            E = np.zeros_like(X)
            E[i, c] = h
            fd[i, c] = (loss(X + E) - loss(X - E)) / (2 * h)
    assert np.abs(fd - dX).max() < 1e-9 * (1 + np.abs(dX).max())
    # and the pieces: <G, J V> = <J^T G, V> for a random direction V
    V = np.random.default_rng(8).standard_normal(X.shape)
    JV = deformer.deform(X + V) - deformer.deform(X)
    assert abs((G * JV).sum() - (dX * V).sum()) < 1e-9 * np.abs(G).sum()


def test_transposes_of_the_pieces(mesh):
    U, T = mesh
    d = U.shape[1]
    rng = np.random.default_rng(9)
    X = meshes.pose(U)
    emb = mbi.embed(U, T, meshes.points(U, 150))
    K = (d + 1) * (d + 2) // 2
    B, G = rng.standard_normal((len(T) * K, d)), rng.standard_normal((150, d))
    GB = mbi.evaluate_transpose(emb, G, len(T))
    assert abs((G * mbi.evaluate(B, emb)).sum() - (GB * B).sum()) < 1e-10
    M = rng.standard_normal((len(U) * d, d))
    GX, GM = mbi.bezier_transpose(U, T, GB)
    assert abs((GB * mbi.bezier_points(U, T, X, M)).sum() - (GX * X).sum() - (GM * M).sum()) < 1e-9
    solver, phong = mbi.ModifiedBI(U, T), mbi.Phong(U, T)
    assert abs((GM * solver.solve(X)).sum() - (solver.solve_transpose(GM) * X).sum()) < 1e-8
    assert abs((GM * phong.M(X)).sum() - (phong.M_transpose(GM) * X).sum()) < 1e-9


try:
    import torch
except ImportError:  # PyTorch is optional: the package imports without it
    torch = None
needs_torch = pytest.mark.skipif(torch is None, reason="PyTorch (python3-torch) is not installed")


@needs_torch
@pytest.mark.parametrize("method", METHODS)
def test_torch_gradcheck(mesh, method):
    import mbi.torch as mt
    U, T = mesh
    deformer = mbi.Deformer(U, T, meshes.points(U, 40, seed=11), method=method)
    X = torch.tensor(meshes.pose(U), dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(lambda Y: mt.deform(deformer, Y), (X,), eps=1e-6, atol=1e-8)
    # a batch of poses
    Xb = torch.tensor(np.stack([meshes.pose(U, seed=s) for s in range(2)]), requires_grad=True)
    assert torch.autograd.gradcheck(mt.Deform(deformer), (Xb,), eps=1e-6, atol=1e-8)


@needs_torch
@pytest.mark.parametrize("method", METHODS)
def test_torch_gradgradcheck(mesh, method):
    import mbi.torch as mt
    U, T = mesh
    deformer = mbi.Deformer(U, T, meshes.points(U, 30, seed=12), method=method)
    X = torch.tensor(meshes.pose(U), dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradgradcheck(lambda Y: mt.deform(deformer, Y), (X,), eps=1e-6, atol=1e-8)
    Xb = torch.tensor(np.stack([meshes.pose(U, seed=s) for s in range(2)]), requires_grad=True)
    assert torch.autograd.gradgradcheck(mt.Deform(deformer), (Xb,), eps=1e-6, atol=1e-8)


@needs_torch
@pytest.mark.parametrize("method", METHODS)
def test_torch_hessian_vector_product(mesh, method):
    # L = sum(W * positions^2) has Hessian J^T diag(2W) J: H V = vjp(2 W * deform(V)), V a direction
    import mbi.torch as mt
    U, T = mesh
    p = 50
    deformer = mbi.Deformer(U, T, meshes.points(U, p, seed=13), method=method)
    rng = np.random.default_rng(14)
    W, V = rng.uniform(0.5, 2, (p, U.shape[1])), rng.standard_normal(U.shape)
    X = torch.tensor(meshes.pose(U), requires_grad=True)
    loss = (torch.from_numpy(W) * mt.deform(deformer, X) ** 2).sum()
    (grad,) = torch.autograd.grad(loss, X, create_graph=True)
    (hv,) = torch.autograd.grad(grad, X, grad_outputs=torch.from_numpy(V))
    expect = deformer.vjp(2 * W * deformer.deform(V))
    assert np.abs(hv.numpy() - expect).max() < 1e-10 * (1 + np.abs(expect).max())
    assert np.abs(expect).max() > 1e-3


@needs_torch
def test_torch_float32_and_module(mesh):
    import mbi.torch as mt
    U, T = mesh
    P = meshes.points(U, 100)
    deformer = mbi.Deformer(U, T, P)
    module = mt.Deform(deformer)
    X = torch.tensor(U, dtype=torch.float32, requires_grad=True)
    positions = module(X)
    assert positions.dtype == torch.float32 and positions.shape == (100, U.shape[1])
    assert torch.allclose(positions, torch.tensor(P, dtype=torch.float32), atol=1e-6)
    target = torch.tensor(P * 1.1, dtype=torch.float32)
    loss = ((positions - target) ** 2).sum()
    loss.backward()
    G = 2 * (deformer.deform(U) - P * 1.1)
    assert np.abs(X.grad.numpy() - deformer.vjp(G)).max() < 1e-4
