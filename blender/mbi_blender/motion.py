"""Rigid motions from Blender's animated transforms, in the form mbi takes them (a kinematic
constraint's or a collider's motion): x(t) = center + velocity s + Rot(axis, rate s)(x0 - center),
s = clamp(t, start, stop) - start.

A Blender transform between two frames is any rigid map; over one frame it is written exactly in
that form (a screw, `step`). A collider takes one motion for the whole run, so its animation is
fitted by one (`fit`) and refused where a frame departs from it.
"""
import numpy as np

FIT_TOLERANCE = 1e-5  # of the object's size: the largest departure of a frame from the fitted motion


def relative(M, M0):
    """The rigid map (4x4) from the pose M0 to the pose M; ValueError when it scales or shears."""
    A = M @ np.linalg.inv(M0)
    R = A[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-5) or np.linalg.det(R) <= 0:
        raise ValueError("changes its scale or shear (mbi moves it rigidly)")
    return A


def rotation(axis, angle):
    """Rot(axis, angle) by Rodrigues' formula (axis need not be unit)."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def axis_angle(R):
    """(unit axis, angle in [0, pi]) of a rotation; the axis (0, 0, 1) for the identity."""
    angle = float(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if np.linalg.norm(w) > 1e-12:
        return w / np.linalg.norm(w), angle
    if angle < 1e-6:
        return np.array([0.0, 0.0, 1.0]), 0.0
    S = (R + np.eye(3)) / 2  # a half turn: R = 2 k k^T - I
    k = S[:, int(np.argmax(np.diag(S)))]
    return k / np.linalg.norm(k), angle


def step(D, center, start, duration):
    """The motion dict that carries points by the rigid map D (4x4) over [start, start + duration]."""
    axis, angle = axis_angle(D[:3, :3])
    c = np.asarray(center, dtype=np.float64)
    velocity = (D[:3, :3] @ c + D[:3, 3] - c) / duration
    return dict(center=c, axis=axis, rate=angle / duration, velocity=velocity, start=start, stop=start + duration)


def pose(m, t):
    """(R, shift) of a motion dict at time t: x = shift + R (x0 - center)."""
    s = min(max(t, m["start"]), m["stop"]) - m["start"]
    R = rotation(m["axis"], m["rate"] * s) if m["rate"] != 0 else np.eye(3)
    return R, m["center"] + m["velocity"] * s


def fit(matrices, dt, probes, first_frame):
    """One motion for a run whose poses are matrices (4x4 each, one a frame, dt s apart), or None when
    static. Relative to the first pose; centered at the object's origin where it starts to move.
    probes: world points at the first pose (the object's box corners) for the check of every frame;
    ValueError naming the frame (first_frame + k) that departs from the motion."""
    A = []
    for k, M in enumerate(matrices):
        try:
            A.append(relative(M, matrices[0]))
        except ValueError as error:
            raise ValueError("at frame %d it %s" % (first_frame + k, error)) from None
    moving = [k for k in range(1, len(A)) if not np.allclose(A[k], A[k - 1], rtol=0, atol=1e-7)]
    if not moving:
        return None
    a, b = moving[0] - 1, moving[-1]
    increments = [axis_angle(A[k][:3, :3] @ A[k - 1][:3, :3].T) for k in range(a + 1, b + 1)]
    axis = max(increments, key=lambda x: x[1])[0]
    angle = sum(theta * np.sign(np.dot(k, axis)) for k, theta in increments)
    duration = (b - a) * dt
    center = matrices[a][:3, 3]
    m = step(A[b], center, a * dt, duration)
    m.update(axis=axis, rate=angle / duration)
    size = max(np.linalg.norm(np.ptp(probes, axis=0)), 1e-12)
    for k in range(len(A)):
        R, shift = pose(m, k * dt)
        expected = probes @ A[k][:3, :3].T + A[k][:3, 3]
        departure = np.abs(shift + (probes - center) @ R.T - expected).max()
        if departure > FIT_TOLERANCE * size:
            raise ValueError("at frame %d it is %.2g of its size away from one constant-velocity rigid "
                             "motion (mbi's colliders take one: key its location and one rotation axis with "
                             "linear interpolation)" % (first_frame + k, departure / size))
    return m
