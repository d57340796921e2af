"""PyTorch autograd for mbi.Deformer: a loss on the dense positions back-propagates to the control
positions X through Deformer.vjp (exact: the positions are linear in X for every method).

    import mbi, mbi.torch
    deformer = mbi.Deformer(U, T, P)
    X = torch.tensor(U, requires_grad=True)
    positions = mbi.torch.deform(deformer, X)      # (p, d), or (frames, p, d) for (frames, n, d)
    loss = ((positions - target) ** 2).sum()
    loss.backward()                                # X.grad = dL/dX

Computed in float64 on the CPU: X of another dtype or device is converted, the result and the
gradient are converted back. Tensors of any strides are taken (expand()ed, t()ed, the
zero-stride gradient of loss.sum()): mbi reads them as numpy views and copies what it cannot
read in place. Importing this module needs torch; importing mbi does not.
"""
import torch

__all__ = ["deform", "Deform", "DeformFunction"]


class DeformFunction(torch.autograd.Function):
    """positions = deformer.deform(X); the backward pass is deformer.vjp(dL/dpositions)."""

    @staticmethod
    def forward(ctx, X, deformer):
        ctx.deformer = deformer
        positions = torch.from_numpy(deformer.deform(_as_numpy(X)))
        return positions.to(X.device, X.dtype)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx, grad):
        dX = torch.from_numpy(ctx.deformer.vjp(_as_numpy(grad)))
        return dX.to(grad.device, grad.dtype), None


def _as_numpy(t):
    """t as a float64 numpy view on the CPU (its strides kept; a lazily negated or conjugated
    tensor materialised, which numpy cannot view)."""
    return t.detach().to("cpu", torch.float64).resolve_conj().resolve_neg().numpy()


def deform(deformer, X):
    """Dense positions of pose X ((n, d) or (frames, n, d)) as a differentiable tensor."""
    return DeformFunction.apply(X, deformer)


class Deform(torch.nn.Module):
    """The Deformer as a module: forward(X) = deform(deformer, X)."""

    def __init__(self, deformer):
        super().__init__()
        self.deformer = deformer

    def forward(self, X):
        return deform(self.deformer, X)
