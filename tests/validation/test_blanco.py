"""Blanco-Lorenzo's angle correction of the half-space numbers (CONTACT's C3 = 4,
conformal.influence.blanco) and CONTACT's groove_li case 5 that uses it."""
from __future__ import annotations


import numpy as np
import pytest

from conformal.errors import InputError
from conformal.influence.blanco import blanco_kernel, linear_fit
from conformal.influence.curved import curved_halfspace_kernel
from conformal.materials import Material
from _paths import DECKS



def _rotation_x(angle: np.ndarray) -> np.ndarray:
    """Rotations about the x axis acting on (x, s, n) components (the test's own oracle)."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(np.shape(angle) + (3, 3))
    R[..., 0, 0] = 1.0
    R[..., 1, 1], R[..., 1, 2] = c, -s
    R[..., 2, 1], R[..., 2, 2] = s, c
    return R


def _strip():
    s = np.arange(6) * 0.3
    delta = np.array([-0.30, -0.12, 0.0, 0.08, 0.25, 0.40])
    K = curved_halfspace_kernel(4, 0.3, s, np.full(6, 0.3), delta, Material.steel(), angle_correction=False)
    return s, delta, K


def test_variant_3_turns_the_displacements_into_the_frame_of_I():
    """Variant 3: B[I, J] = R(alpha_J - alpha_I) A[I, J] (rows s, n turned), computed here with the
    rotation matrices of conformal.influence.curved."""
    _, delta, K = _strip()
    a = delta[None, :] - delta[:, None]
    ref = np.einsum("IJab,kIJbc->kIJac", _rotation_x(a), K)
    assert np.allclose(blanco_kernel(K, delta, 3), ref, rtol=0, atol=1e-15 * np.abs(K).max())


def test_variant_4_is_the_projects_turned_frames():
    """Variant 4, R(alpha/2) A R(alpha/2), equals the project's own turned-frame numbers
    (influence = "halfspace") for alpha = delta, CONTACT's inclination (groove_li case 5 below):
    both turn the frames in the sense the FE bodies have (test_curved_influence, frames21)."""
    s, delta, K = _strip()
    turned = curved_halfspace_kernel(4, 0.3, s, np.full(6, 0.3), delta, Material.steel())
    scale = np.abs(turned).max()
    assert np.abs(blanco_kernel(K, delta, 4) - turned).max() < 1e-14 * scale
    assert np.abs(blanco_kernel(K, -delta, 4) - turned).max() > 0.05 * scale


def test_no_change_of_inclination_leaves_the_half_space_numbers():
    _, delta, K = _strip()
    for v in (1, 2, 3, 4):
        assert np.allclose(blanco_kernel(K, np.full(6, 0.3), v), K, rtol=0, atol=1e-15 * np.abs(K).max())
    # variants 1 and 2 differ in B_xn only
    b1, b2 = blanco_kernel(K, delta, 1), blanco_kernel(K, delta, 2)
    diff = np.abs(b1 - b2).max(axis=(0, 1, 2))
    assert diff[0, 2] > 0 and np.delete(diff.ravel(), 2).max() == 0.0
    with pytest.raises(InputError, match="variant must be one of 1-4"):
        blanco_kernel(K, delta, 5)
    assert linear_fit(np.arange(4.0), np.array([0.0, 1.0, 2.0, 3.0])) == pytest.approx([0, 1, 2, 3])


def test_scene_keys():
    from conformal.scene import scene_from_dict

    base = {"geometry": {"kind": "hertz", "a": 1.0, "b": 1.0}, "load": {"normal_force": 100.0}}
    with pytest.raises(InputError, match="halfspace_blanco"):
        scene_from_dict({**base, "model": {"theory": "exact", "influence": "halfspace_blanco"}})
    # the documented creepage "wheel_surface" (CONTACT's rigid slip) is read with any influence numbers
    assert scene_from_dict({**base, "model": {"theory": "exact", "creepage": "wheel_surface"}}).model.options[
        "creepage"] == "wheel_surface"
    with pytest.raises(InputError, match=r"\[model\] blanco_variant: must be one of 1, 2, 3, 4"):
        scene_from_dict({**base, "model": {"theory": "conformal", "influence": "halfspace_blanco", "blanco_variant": 5}})


@pytest.mark.slow
def test_groove_li_case_5_against_contact():
    """groove_li case 5 (R10 wheel in the R10.25 groove, 10 kN, free rolling, C3 = 4 with
    IF_METH = 1, VARIANT = 3; about 70 s): CONTACT's Blanco numbers lower pmax by 1.8 % and raise
    the free-rolling pitch creepage by 2.8 % against case 1 (C3 = 2); the project with the same
    correction: pmax within 0.1 %, TILDE_FN 0.05 %, the pitch 0.2 %, elements exactly.  With the
    inclination's sign reversed pmax is 3.1 % and the pitch -2.3 % off."""
    from conformal.contact_inp.deck import read_deck, solve_deck
    from conformal.contact_inp.refout import compare_conformal, read_ref_out_wheelrail

    parsed = read_deck(DECKS / "groove_li.inp")
    ref = read_ref_out_wheelrail((DECKS / "groove_li.ref_out").read_text(encoding="utf-8"))
    (d,) = list(solve_deck(parsed, cases=[5]))
    dev = compare_conformal(d, ref[5], nomrad=420.0)
    assert abs(dev["patch1.pmax"]) < 0.1 and abs(dev["patch1.FN"]) < 0.05 and dev["patch1.n_contact"] == 0.0
    assert abs(dev["pitch_creepage"]) < 0.2
