"""Arm: positions, Jacobians and parameters against the command line and
against each other."""

import numpy as np
import pytest

import aacmm
from conftest import ARM, POSES, longest_stall, read_poses


def test_positions_equal_the_cli_points_output(cli, arm):
    labels, q = read_poses()
    xyz = arm.positions(np.array(q), angle_unit="deg")
    assert xyz.shape == (len(q), 3) and xyz.dtype == np.float64
    ours = ["point,x,y,z"] + [
        f"{l},{x:.6f},{y:.6f},{z:.6f}" for l, (x, y, z) in zip(labels, xyz)
    ]
    assert cli("points", "--arm", ARM, "--data", POSES).splitlines() == ours


def test_batches_in_any_layout_and_chunking_give_the_same_bits(arm):
    rng = np.random.default_rng(7)
    q = rng.uniform(-np.pi, np.pi, size=(40_000, 6))  # more than one chunk
    all_at_once = arm.positions(q)
    pieces = np.concatenate([arm.positions(q[i : i + 9_999]) for i in range(0, len(q), 9_999)])
    assert np.array_equal(all_at_once, pieces)
    one = arm.positions(q[12_345])
    assert one.shape == (3,) and np.array_equal(one, all_at_once[12_345])
    assert np.array_equal(arm.positions(np.asfortranarray(q)), all_at_once)
    strided = np.repeat(q, 2, axis=0)[::2]
    assert not strided.flags.c_contiguous
    assert np.array_equal(arm.positions(strided), all_at_once)
    assert np.array_equal(arm.positions(q[:5].tolist()), all_at_once[:5])
    assert np.array_equal(arm.positions(q[:5].astype(np.float32)), arm.positions(q[:5].astype(np.float32).astype(float)))
    assert arm.positions(np.zeros((0, 6))).shape == (0, 3)


def test_jacobians_are_derivatives_of_the_positions(arm):
    rng = np.random.default_rng(1)
    q = rng.uniform(-3, 3, size=(50, 6))
    p, jac = arm.jacobians(q)
    assert p.shape == (50, 3) and jac.shape == (50, 3, 27)
    assert np.allclose(p, arm.positions(q), atol=1e-9, rtol=0)
    params = arm.params
    h = 1e-6
    for c in range(27):
        up, down = params.copy(), params.copy()
        up[c] += h
        down[c] -= h
        numeric = (
            aacmm.Arm.from_params(6, up).positions(q) - aacmm.Arm.from_params(6, down).positions(q)
        ) / (2 * h)
        assert np.allclose(jac[:, :, c], numeric, atol=1e-4 * max(1.0, np.abs(numeric).max()))
    # One pose drops the pose axis.
    p1, j1 = arm.jacobians(q[3])
    assert p1.shape == (3,) and j1.shape == (3, 27)
    assert np.array_equal(j1, jac[3]) and np.array_equal(p1, p[3])


def test_joint_jacobian_is_the_zero_offset_columns(arm):
    rng = np.random.default_rng(2)
    q = rng.uniform(-3, 3, size=(20, 6))
    p, jq = arm.joint_jacobian(q)
    _, jac = arm.jacobians(q)
    assert jq.shape == (20, 3, 6)
    theta = [arm.param_names.index(f"theta{j + 1}") for j in range(6)]
    # ∂p/∂q_j = ∂p/∂theta_j: the joint angle is q + theta.
    assert np.allclose(jq, jac[:, :, theta], atol=1e-9, rtol=0)
    assert np.allclose(p, arm.positions(q), atol=1e-9, rtol=0)
    p1, j1 = arm.joint_jacobian(q[0])
    assert p1.shape == (3,) and j1.shape == (3, 6) and np.array_equal(j1, jq[0])


def test_param_names_refuses_joint_counts_without_a_kernel():
    # 0 divided by zero (a panic past `except Exception`), 2**62 wrapped
    # 4·n + 3 to three names, 13 is past the longest chain.
    for joints in (0, 13, 2**62):
        with pytest.raises(aacmm.UnsupportedError, match=f"joints = {joints}: .*chains of 1 to 12 joints"):
            aacmm.param_names(joints)
    assert len(aacmm.param_names(7)) == 31
    assert len(aacmm.param_names(5)) == 23


def test_parameters_round_trip(arm):
    names = aacmm.param_names(6)
    assert names[:2] == ["a1", "a2"] and names[-3:] == ["Bx", "By", "Bz"] and len(names) == 27
    again = aacmm.Arm.from_params(6, arm.params, name="copy")
    assert np.array_equal(again.params, arm.params)
    assert again.name == "copy" and again.source == "<parameters>"
    q = np.linspace(-2, 2, 60).reshape(10, 6)
    assert np.array_equal(again.positions(q), arm.positions(q))
    assert arm.to_dict()["Bz"] == arm.params[-1]
    assert arm.positions(np.degrees(q), angle_unit="deg").shape == (10, 3)
    assert "[[joint]]" in arm.to_toml()
    assert len(arm.limits) == 6


def test_the_gil_is_released_during_a_batch(arm):
    q = np.random.default_rng(3).uniform(-3, 3, size=(1_000_000, 6))
    took, stall = longest_stall(lambda: arm.positions(q))
    assert took > 0.005, took
    assert stall < took / 2, (stall, took)
