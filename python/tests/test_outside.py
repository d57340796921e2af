"""Dense points outside the control mesh, reported as `mbi deform` reports them: an
mbi.OutsideWarning naming how many and the farthest, the counts as Deformer attributes, and
max_outside= refusing points farther out than that fraction of the model size (--max-outside)."""
import warnings

import numpy as np
import pytest

import mbi
import meshes


@pytest.fixture
def far_points():
    """(U, T, P): 500 points inside the jittered box [0,2]x[0,1]x[0,1], then 100 17 units beyond x = 2."""
    U, T = meshes.jittered(3)
    rng = np.random.default_rng(4)
    inside = rng.uniform([0.1, 0.1, 0.1], [1.9, 0.9, 0.9], (500, 3))
    far = rng.uniform([0.2, 0.2, 0.2], [0.8, 0.8, 0.8], (100, 3)) + [19.0, 0, 0]
    return U, T, np.vstack([inside, far])


def test_points_inside_do_not_warn():
    U, T = meshes.jittered(3)
    P = np.random.default_rng(4).uniform([0.1, 0.1, 0.1], [1.9, 0.9, 0.9], (300, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        deformer = mbi.Deformer(U, T, P, max_outside=0)
    assert deformer.outside_points == 0 and deformer.max_outside_distance == 0


@pytest.mark.parametrize("method", ["bi", "modified-bi", "phong"])
def test_points_outside_warn_and_are_counted(far_points, method):
    U, T, P = far_points
    with pytest.warns(mbi.OutsideWarning) as record:
        deformer = mbi.Deformer(U, T, P, method=method)
    assert len(record) == 1
    message = str(record[0].message)
    assert message.startswith("100 of 600 points lie outside the control mesh (farthest 17.")
    assert message.endswith("they follow the nearest element by extrapolation")
    assert record[0].filename == __file__  # the warning points at the caller's line
    assert deformer.outside_points == 100 == len(deformer.embedding.outside)
    assert 17.7 < deformer.max_outside_distance < 17.9  # 0.8 beyond x = 2 at most 19.8 - 2
    assert issubclass(mbi.OutsideWarning, UserWarning)


def test_max_outside_refuses_far_points(far_points):
    U, T, P = far_points
    size = np.linalg.norm(P.max(0) - P.min(0))
    with pytest.raises(mbi.Error) as e:
        mbi.Deformer(U, T, P, max_outside=0.1)
    text = str(e.value)
    assert text.startswith("P: 100 of 600 points lie farther outside the control mesh (U, T) than max_outside=0.1 "
                           f"x the model size {size:.4g}")
    assert "the worst, point" in text
    worst = int(text.split("point ")[-1].split(",")[0])
    assert worst >= 500  # one of the far points
    # a tolerance beyond the farthest point keeps them all, with the warning
    with pytest.warns(mbi.OutsideWarning):
        deformer = mbi.Deformer(U, T, P, max_outside=17.9 / size)
    assert deformer.outside_points == 100


def test_warnings_as_errors_refuse(far_points):
    U, T, P = far_points
    with warnings.catch_warnings():
        warnings.simplefilter("error", mbi.OutsideWarning)
        with pytest.raises(mbi.OutsideWarning):
            mbi.Deformer(U, T, P)


@pytest.mark.parametrize("bad", [-0.1, float("nan"), float("inf")])
def test_max_outside_must_be_finite_and_not_negative(far_points, bad):
    U, T, P = far_points
    with pytest.raises(mbi.Error, match="max_outside must be a finite number >= 0"):
        mbi.Deformer(U, T, P, max_outside=bad)


def test_embed_warns_counts_and_refuses_as_the_deformer_does(far_points):
    U, T, P = far_points
    with pytest.warns(mbi.OutsideWarning) as record:
        emb = mbi.embed(U, T, P)
    assert len(record) == 1 and record[0].filename == __file__
    assert str(record[0].message).startswith("100 of 600 points lie outside the control mesh (farthest 17.")
    assert len(emb.outside) == 100 and 17.7 < emb.max_outside_distance < 17.9
    with pytest.raises(mbi.Error, match=r"^P: 100 of 600 points lie farther outside the control mesh \(U, T\) "
                                        r"than max_outside=0.1 x the model size"):
        mbi.embed(U, T, P, max_outside=0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mbi.embed(U, T, P[:500], max_outside=0)  # inside: no warning, nothing refused


def test_frame_pipeline_warns_counts_and_refuses_as_the_deformer_does(far_points):
    U, T, P = far_points
    with pytest.warns(mbi.OutsideWarning) as record:
        pipe = mbi.FramePipeline(U, T, P)
    assert len(record) == 1 and record[0].filename == __file__
    assert pipe.outside_points == 100 and 17.7 < pipe.max_outside_distance < 17.9
    with pytest.raises(mbi.Error, match=r"^P: 100 of 600 points lie farther outside"):
        mbi.FramePipeline(U, T, P, max_outside=0.1)
    with pytest.raises(mbi.Error, match="max_outside must be a finite number >= 0"):
        mbi.FramePipeline(U, T, P, max_outside=-1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mbi.FramePipeline(U, T, P[:500], max_outside=0).outside_points == 0
