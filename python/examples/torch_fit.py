"""PyTorch optimises the control mesh so that the dense model matches a target shape: the dense
points P, moved by a known smooth bend and twist, are the target; the control positions X
start at rest, and a loss on the dense points back-propagates to X through mbi.torch.deform
(Deformer.vjp, exact). The loss falls by more than a factor of 1000.

    PYTHONPATH=build/release/python python3 python/examples/torch_fit.py [--method M]
"""
import argparse

import numpy as np
import numpy.typing as npt
import torch

import mbi
import mbi.torch


def bend_twist(P: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The target shape: a twist of 60 degrees along x and a bend of the bar's axis."""
    x, y, z = P[:, 0], P[:, 1] - 0.5, P[:, 2] - 0.5
    a = np.pi / 3 * x / 3.0
    return np.stack([x, 0.5 + np.cos(a) * y - np.sin(a) * z, 0.5 + np.sin(a) * y + np.cos(a) * z + 0.1 * x**2], 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--method", default="modified-bi", choices=mbi.METHODS)
    parser.add_argument("--points", type=int, default=5000)
    parser.add_argument("--iterations", type=int, default=30)
    args = parser.parse_args()

    U, T = mbi.box_mesh(6, 2, 2, (3.0, 1.0, 1.0))
    P = np.random.default_rng(1).uniform([0, 0, 0], [3, 1, 1], size=(args.points, 3))
    model = mbi.torch.Deform(mbi.Deformer(U, T, P, method=args.method))
    target = torch.from_numpy(bend_twist(P))

    X = torch.tensor(U, requires_grad=True)
    optimizer = torch.optim.LBFGS([X], lr=1, max_iter=args.iterations, line_search_fn="strong_wolfe")

    def loss_fn() -> torch.Tensor:
        loss: torch.Tensor = ((model(X) - target) ** 2).sum(1).mean()  # mean squared distance, m^2
        return loss

    def closure() -> float:
        optimizer.zero_grad()
        loss = loss_fn()
        loss.backward()  # type: ignore[no-untyped-call]  # torch 1.13 leaves backward() unannotated
        return loss.item()

    first = loss_fn().item()
    optimizer.step(closure)
    last = loss_fn().item()
    print(f"{args.method}: mean squared distance to the target {first:.3e} -> {last:.3e} m^2 "
          f"({first / last:.0f}x lower) in {args.iterations} L-BFGS iterations")
    assert first / last > 1000, "the loss falls by more than 1000x"
    print("ok: the control mesh was fitted through the dense model's loss")


if __name__ == "__main__":
    main()
