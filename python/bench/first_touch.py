"""The first touch of a new 600 MB numpy array in this new process, four ways: written by one
fill (none), mapped first by two threads writing zeros (memset2, what mbi does for a new result
of 4 MB or more), or by the kernel with madvise(MADV_POPULATE_WRITE) on two threads (populate2)
or one (populate1); on huge pages (numpy's madvise(MADV_HUGEPAGE), its default) or on 4 KB
pages (4k). Prints the seconds of the mapping, of the fill after it, and of a second fill.

    python3 python/bench/first_touch.py MODE huge|4k      # MODE: none, memset2, populate2, populate1
    for m in none memset2 populate2 populate1; do for h in huge 4k; do python3 python/bench/first_touch.py $m $h; done; done
"""
import ctypes
import sys
import threading
import time

import numpy as np

MADV_POPULATE_WRITE = 23
HUGE_PAGE = 2 << 20
libc = ctypes.CDLL(None, use_errno=True)
libc.madvise.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int]
libc.memset.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t]


def parts(base, nbytes, n):
    """n ranges [lo, hi) of the array, cut at 2 MB-aligned addresses (as mbi cuts them)."""
    cuts = [base] + [(base + nbytes * k // n) // HUGE_PAGE * HUGE_PAGE for k in range(1, n)] + [base + nbytes]
    return list(zip(cuts[:-1], cuts[1:]))


def populate(lo, hi):
    first = (lo + 4095) // 4096 * 4096
    if libc.madvise(first, hi - first, MADV_POPULATE_WRITE) != 0:
        raise OSError(ctypes.get_errno(), "madvise(MADV_POPULATE_WRITE)")
    libc.memset(lo, 0, first - lo)


def memset(lo, hi):
    libc.memset(lo, 0, hi - lo)


def on_threads(f, ranges):
    threads = [threading.Thread(target=f, args=r) for r in ranges]  # ctypes lets the GIL go
    for t in threads:
        t.start()
    for t in threads:
        t.join()


def main():
    mode, pages = sys.argv[1], sys.argv[2]
    np.core.multiarray._set_madvise_hugepage(pages == "huge")
    t0 = time.perf_counter()
    a = np.empty(600_000_000 // 8)
    base, nbytes = a.ctypes.data, a.nbytes
    if mode == "memset2":
        on_threads(memset, parts(base, nbytes, 2))
    elif mode == "populate2":
        on_threads(populate, parts(base, nbytes, 2))
    elif mode == "populate1":
        populate(base, base + nbytes)
    t1 = time.perf_counter()
    a.fill(1.0)
    t2 = time.perf_counter()
    a.fill(2.0)
    t3 = time.perf_counter()
    print(f"{mode:10s} {pages:4s} mapping {t1 - t0:.3f} s, first fill {t2 - t1:.3f} s, total {t2 - t0:.3f} s, "
          f"second fill {t3 - t2:.3f} s")


if __name__ == "__main__":
    main()
