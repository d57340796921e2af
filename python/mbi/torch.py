"""PyTorch autograd for mbi.Deformer: a loss on the dense positions back-propagates to the control
positions X through Deformer.vjp (exact: the positions are linear in X for every method).

    import mbi, mbi.torch
    deformer = mbi.Deformer(U, T, P)
    X = torch.tensor(U, requires_grad=True)
    positions = mbi.torch.deform(deformer, X)      # (p, d), or (frames, p, d) for (frames, n, d)
    loss = ((positions - target) ** 2).sum()
    loss.backward()                                # X.grad = dL/dX

Differentiable to any order (the backward is VjpFunction, whose backward is deform again):
double backward gives Hessian-vector products. Computed in float64 on the CPU: a float64 CPU
tensor is shared with numpy both ways, without a copy; X of another dtype or device is
converted, the result and the gradient are converted back. X may be a numpy array (or anything numpy.asarray takes): it is
taken as a tensor that needs no gradient. Tensors of any strides are taken (expand()ed, t()ed,
the zero-stride gradient of loss.sum()): mbi reads them as numpy views and copies what it cannot
read in place. Importing this module needs torch; importing mbi does not.
"""
from typing import Any, Callable, Optional, Tuple

import numpy as np
import numpy.typing as npt
import torch

from . import _mbi

__all__ = ["deform", "Deform", "DeformFunction", "VjpFunction"]


class DeformFunction(torch.autograd.Function):
    """positions = deformer.deform(X); the backward pass is deformer.vjp(dL/dpositions), itself
    differentiable (VjpFunction), so that second derivatives and Hessian-vector products flow."""

    @staticmethod
    def forward(ctx: Any, X: torch.Tensor, deformer: _mbi.Deformer) -> torch.Tensor:  # type: ignore[override]
        ctx.deformer = deformer
        return _apply(deformer.deform, X)

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor) -> Tuple[torch.Tensor, None]:  # type: ignore[override]
        dX: Optional[torch.Tensor] = VjpFunction.apply(grad, ctx.deformer)
        assert dX is not None
        return dX, None


class VjpFunction(torch.autograd.Function):
    """dL/dX = deformer.vjp(G): the transpose J^T of the linear map J = deform, so its backward is
    J itself, deformer.deform(dL/d(dL/dX)), and every higher derivative is J or J^T again."""

    @staticmethod
    def forward(ctx: Any, G: torch.Tensor, deformer: _mbi.Deformer) -> torch.Tensor:  # type: ignore[override]
        ctx.deformer = deformer
        return _apply(deformer.vjp, G)

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor) -> Tuple[torch.Tensor, None]:  # type: ignore[override]
        dG: Optional[torch.Tensor] = DeformFunction.apply(grad, ctx.deformer)
        assert dG is not None
        return dG, None


def _apply(f: Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float64]], t: torch.Tensor) -> torch.Tensor:
    """f (deform or vjp) of t in float64 on the CPU, returned in t's dtype and on its device."""
    return torch.from_numpy(f(_as_numpy(t))).to(t.device, t.dtype)


def _as_numpy(t: torch.Tensor) -> npt.NDArray[np.float64]:
    """t as a float64 numpy view on the CPU (its strides kept; a lazily negated or conjugated
    tensor materialised, which numpy cannot view)."""
    view: npt.NDArray[np.float64] = t.detach().to("cpu", torch.float64).resolve_conj().resolve_neg().numpy()
    return view


def _as_tensor(X: Any) -> torch.Tensor:
    """X as a tensor: a tensor as it is; a numpy array or list as a float64 tensor sharing its memory
    where it can (integer positions become float64)."""
    if isinstance(X, torch.Tensor):
        return X
    array = np.asarray(X)
    if array.dtype.kind in "iub":
        array = array.astype(np.float64)
    return torch.as_tensor(array)


def deform(deformer: _mbi.Deformer, X: Any) -> torch.Tensor:
    """Dense positions of pose X ((n, d) or (frames, n, d): a tensor, or a numpy array) as a
    differentiable tensor."""
    result: Optional[torch.Tensor] = DeformFunction.apply(_as_tensor(X), deformer)
    assert result is not None
    return result


class Deform(torch.nn.Module):
    """The Deformer as a module: forward(X) = deform(deformer, X)."""

    def __init__(self, deformer: _mbi.Deformer) -> None:
        super().__init__()
        self.deformer = deformer

    def forward(self, X: Any) -> torch.Tensor:
        return deform(self.deformer, X)
