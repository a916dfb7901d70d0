"""Bad input (issue 9): values of the wrong type are refused with a message naming the field.

``friction = "0.7"`` and ``friction = True`` used to be converted silently by ``np.array(...,
dtype=float)`` (the second gives friction 1.0 and ``lam1 = 0``).
"""

import numpy as np
import pytest

import shakedown as sd

A, B, C = np.eye(2) * 2.0, np.zeros((2, 2)), np.eye(2) * 3.0


@pytest.mark.parametrize("friction", ["0.7", True, False, np.bool_(True), ["0.7", 0.5],
                                      [True, 0.5], np.array(["0.7", "0.5"])])
def test_friction_of_the_wrong_type_is_refused(friction):
    with pytest.raises(sd.InputError) as info:
        sd.DiscreteSystem(A, B, C, friction=friction)
    msg = str(info.value)
    assert "friction" in msg and "number" in msg and repr(friction)[:20] in msg


@pytest.mark.parametrize("friction", [0.7, 1, np.float32(0.25), [0.5, 0.7], np.array([0, 2]),
                                      (0.1, 0.2)])
def test_numbers_are_still_accepted(friction):
    s = sd.DiscreteSystem(A, B, C, friction=friction)
    np.testing.assert_array_equal(s.friction, np.broadcast_to(np.asarray(friction, float), (2,)))


def test_wrong_length_q0_is_named_q0_when_the_system_is_known():
    # the Python API cannot know which of q0, p0 is wrong: it names both with their lengths
    with pytest.raises(sd.ShapeError, match=r"q0 has 3 entries but p0 has 2"):
        sd.LoadCycle.from_harmonics(q0=[0.1, -0.1, 0.0], p0=[1.0, 1.0], q_cos=[0.5, 0.0])


def test_system_keeps_one_copy_of_K_and_not_the_callers_arrays():
    """A, B, C are read-only views of the one symmetric K (4 N^2 numbers held, not 7 N^2), and
    the caller's arrays are copied: changing them later does not change the system."""
    import numpy as np

    import shakedown as sd

    A = np.array([[2.0, 0.5], [0.5, 2.0]])
    B = np.array([[0.1, 0.2], [0.0, 0.3]])
    C = np.array([[3.0, 0.0], [0.0, 3.0]])
    s = sd.DiscreteSystem(A, B, C, friction=0.3)
    assert all(np.shares_memory(M, s.K) for M in (s.A, s.B, s.C))
    assert not any(M.flags.writeable for M in (s.A, s.B, s.C, s.K))
    np.testing.assert_array_equal(s.K, np.block([[A, B], [B.T, C]]))
    A[0, 0] = B[0, 0] = C[0, 0] = 99.0
    assert s.A[0, 0] == 2.0 and s.B[0, 0] == 0.1 and s.C[0, 0] == 3.0
