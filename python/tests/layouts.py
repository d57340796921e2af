"""Arrays laid out the ways numpy and other libraries make them: C and Fortran order, strided
and reversed views, zero strides (broadcast), rows that overlap (as_strided), unaligned memory,
other byte orders, read-only. `arrange` makes a view of given values in one of these layouts;
the tests compare each call on it with the same call on a contiguous copy."""
import numpy as np
from numpy.lib.stride_tricks import as_strided

# Layouts that hold any values (an output may be any of these).
WRITABLE = ["C", "F", "steps", "reversed", "transposed", "unaligned", "frames apart"]
# Layouts of inputs only: the view's values differ from those given (read them from the view).
READ_ONLY = ["broadcast rows", "broadcast cols", "overlapping rows"]
# Zero strides first: hypothesis draws the first entries of a list most often.
LAYOUTS = READ_ONLY + WRITABLE

FLOATS = ["<f8", ">f8", "<f4", ">f4", "<f2", "longdouble"]
INTEGERS = ["<i8", ">i8", "<i4", "<u2", "<u8", "<i2"]


def _strided(shape, dtype, steps):
    """A writable view of `shape` taking every steps[k]-th element of a larger zeroed array."""
    big = np.zeros([n * s for n, s in zip(shape, steps)], dtype)
    return big[tuple(slice(None, None, s) for s in steps)]


def arrange(values, layout, dtype=None, readonly=False):
    """A view in `layout` (one of LAYOUTS) of `values` stored as `dtype` (default: values').
    For the READ_ONLY layouts the view holds values derived from them."""
    v = np.asarray(values)
    dtype = np.dtype(dtype or v.dtype)
    with np.errstate(over="ignore"):  # float16 holds up to 65504: larger values become inf
        v = v.astype(dtype)
    last = (slice(None),) * (v.ndim - 2)  # a batch's frame axis stays as it is
    if layout == "C":
        a = np.ascontiguousarray(v)
    elif layout == "F":
        a = np.asfortranarray(v)
    elif layout == "steps":
        a = _strided(v.shape, dtype, [2] * (v.ndim - 2) + [3, 2])
        a[...] = v
    elif layout == "reversed":
        a = _strided(v.shape, dtype, [1] * v.ndim)[..., ::-1, ::-1]
        a[...] = v[..., ::-1, ::-1][..., ::-1, ::-1]
    elif layout == "transposed":  # the last axis slowest
        a = np.moveaxis(np.ascontiguousarray(np.moveaxis(v, -1, 0)), 0, -1)
    elif layout == "unaligned":
        raw = bytearray(v.nbytes + 1)
        a = np.frombuffer(raw, dtype, count=v.size, offset=1).reshape(v.shape)
        a[...] = v
    elif layout == "frames apart":  # rows one stride apart, frames (or the rows) further
        a = _strided((v.shape[0] * 2,) + v.shape[1:], dtype, [1] * v.ndim)[::2]
        a[...] = v
    elif layout == "broadcast rows":
        a = np.broadcast_to(v[last + (slice(0, 1),)], v.shape)
    elif layout == "broadcast cols":
        a = np.broadcast_to(v[..., :1], v.shape)
    elif layout == "overlapping rows":  # row i starts one item after row i - 1
        flat = np.ascontiguousarray(v).ravel()
        shape, item = v.shape, dtype.itemsize
        strides = (item,) * v.ndim if v.ndim == 2 else (shape[1] * item, item, item)
        a = as_strided(flat, shape, strides, writeable=False)
    else:
        raise ValueError(layout)
    if readonly and a.flags.writeable:
        a.flags.writeable = False
    return a


def contiguous(a):
    """The same values as a C-order float64 (or int64 for integers) array of its own."""
    kind = np.dtype(a.dtype).kind
    return np.array(a, dtype=np.int64 if kind in "iu" else np.float64, order="C")
