"""A real model deformed with a generated cage, its texture kept: mbi.cage builds a control mesh
around the model, mbi.Simulator makes it sag under gravity (clamped on its back), a FramePipeline
moves the model's vertices with modified-BI, and the last frame is written as an OBJ that keeps
the file's texture coordinates, groups and materials (mbi.Surface.with_positions).

    PYTHONPATH=build/release/python python3 python/examples/deform_model.py \
        --model /work/shared/models/spot.obj --out out/spot_sag.obj [--vertices N] [--frames F]
"""
import argparse
import os

import numpy as np
import numpy.typing as npt

import mbi


def texture_coordinates(path: str) -> npt.NDArray[np.float64]:
    """The `vt` records of an OBJ file, as read from its text."""
    with open(path) as f:
        return np.array([[float(x) for x in line.split()[1:]] for line in f if line.startswith("vt ")])


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    models = os.environ.get("MBI_MODELS_DIR", "")
    parser.add_argument("--model", default=os.path.join(models, "spot.obj"), help="an OBJ with texture coordinates")
    parser.add_argument("--out", default="spot_sag.obj")
    parser.add_argument("--vertices", type=int, default=200, help="control vertices of the cage")
    parser.add_argument("--frames", type=int, default=30, help="frames of 1/30 s")
    a = parser.parse_args()

    mesh = mbi.read_surface(a.model)                     # V (n, 3), F; the rest of the file kept
    cage = mbi.cage(mesh.V, mesh.F, vertices=a.vertices)  # as `mbi cage` builds it
    U, T = cage
    size = np.linalg.norm(U.max(0) - U.min(0))
    print(f"{a.model}: {len(mesh.V)} vertices; cage {len(U)} vertices, {len(T)} tetrahedra ({cage.mesher})")

    # the model's units taken as metres: a soft rubber-like body (Pa, kg/m^3)
    sim = mbi.Simulator(U, T, youngs_modulus=5e5, poisson_ratio=0.4, density=1000, dt=1 / 30,
                        gravity=(0, -9.81, 0), mass_damping=1.0)
    back = U[:, 2] <= U[:, 2].min() + 0.15 * (U[:, 2].max() - U[:, 2].min())
    sim.fix(back)  # a boolean mask of the control vertices
    pipe = mbi.FramePipeline(U, T, mesh.V, sim, method="modified-bi")
    for _ in range(a.frames + 1):  # frame 0 is the rest pose
        result = pipe.step()
        if not result:
            raise SystemExit(f"frame {result.frame}: {result.message}")
    moved = np.linalg.norm(pipe.positions - mesh.V, axis=1).max()
    mbi.write_surface(a.out, mesh.with_positions(pipe.positions))
    print(f"{a.out}: the last frame (frame {pipe.frame}), largest displacement {moved / size:.1%} of the model's size")

    uv_in, uv_out = texture_coordinates(a.model), texture_coordinates(a.out)
    if len(uv_in) and uv_in.shape == uv_out.shape and np.array_equal(uv_in, uv_out) and moved > 0:
        print(f"ok: the deformed model keeps its {len(uv_in)} texture coordinates")


if __name__ == "__main__":
    main()
