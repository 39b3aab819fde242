"""The finger's closing-plane kinematics: pre-shape, sweep, one contact plane, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from grip_env.planning.finger import (
    JOINT2_MAX,
    JOINT3_MAX,
    closing_sweep_depth,
    fingertip_in_plane,
    opening_posture,
    pad_contact_in_plane,
    planar_contacts,
    sweep_depth,
)

joints = st.tuples(st.floats(0.3, JOINT2_MAX), st.floats(0.0, JOINT3_MAX))


@given(joints, st.floats(2.0, 20.0))
def test_the_preshape_opens_the_fingertip_by_the_gap(q, gap):
    q2, q3 = np.array([q[0]]), np.array([q[1]])
    open2, open3 = opening_posture(q2, q3, gap)
    assert (open2 <= q2).all() and (open3 <= q3).all()
    reach, _ = fingertip_in_plane(q2, q3)
    opened, _ = fingertip_in_plane(open2, open3)
    fully_open, _ = fingertip_in_plane(*opening_posture(q2, q3, 1e6))
    # the gap is met to 0.01 mm, unless even the widest pre-shape cannot open that far
    assert opened[0] == pytest.approx(min(reach[0] + gap, fully_open[0]), abs=1e-2)


def test_the_tabulated_sweep_is_the_direct_one():
    rng = np.random.default_rng(0)
    q2, q3 = rng.uniform(0, JOINT2_MAX, 2000), rng.uniform(0, JOINT3_MAX, 2000)
    open2, open3 = opening_posture(q2, q3, 12.0)
    direct = sweep_depth(open2, open3, q2, q3)
    np.testing.assert_allclose(closing_sweep_depth(q2, q3, 12.0), direct, atol=0.1)


def test_planar_contacts_put_every_pad_in_one_plane():
    reaches = np.array([[30.0, 30.0, 40.0], [60.0, 55.0, 70.0], [500.0, 30.0, 30.0]])
    posture, found = planar_contacts(reaches, 30.0, 8.0, 4.0, 5.0, 12.0)
    assert found.tolist() == [True, True, False]  # no finger reaches half a metre
    reach, height = pad_contact_in_plane(posture.q2[:2], posture.q3[:2])
    np.testing.assert_allclose(reach, reaches[:2], atol=1e-6)
    pad_z = (posture.plane_z_mm + posture.height_mm)[:2, None] - height
    np.testing.assert_allclose(pad_z, np.repeat(posture.plane_z_mm[:2, None], 3, axis=1), atol=1e-6)
    assert ((posture.plane_z_mm[:2] >= 15.0) & (posture.plane_z_mm[:2] <= 23.0)).all()


def test_reaches_of_the_wrong_shape_are_refused():
    with pytest.raises(ValueError, match=r"shape \(3,\) or \(n, 3\)"):
        planar_contacts(np.zeros((4, 2)), 30.0, 8.0, 4.0, 5.0, 12.0)
