"""DFKI's published parameter sets of RealAIGym's design C.1 and A.0 robots, the comparison for identification.

From ``data/system_identification/identified_parameters/design_{C.1,A.0}/model_*/model_parameters.yml``
of github.com/dfki-ric-underactuated-lab/double_pendulum (commit 1e8544e; BSD-3-Clause, (c) DFKI
GmbH Robotics Innovation Center). C.1: model 1.0 is the plant of leaderboard v2, model 1.1 (1.0
without friction and rotor inertia) that of v3. A.0: models 1.0, 2.0 and 2.1 (2.0 without friction
and rotor inertia, with the pendubot's torque limits 6 / 0 N.m). Torque limits (``tl1, tl2``) are
not model parameters here.

Physical consistency (:func:`pendulab.model.robot.check_robot_params`: a link's inertia about its
joint at least ``m r^2``): C.1's 2.0 and 3.0 fail it (``I2`` 0.051 < ``m2 r2^2`` 0.074 and 0.010 <
0.024 kg.m^2); C.1's 1.0, 1.1 and all three A.0 sets pass (A.0 1.0: ``I1 - m1 r1^2`` = 0.0087,
``I2 - m2 r2^2`` = 0.0079 kg.m^2; 2.0 and 2.1: 0.0031 and 0.0035 kg.m^2).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

__all__ = ["DFKI_C1", "C1_GEOMETRY", "DFKI_A0", "A0_GEOMETRY"]

_M10 = {
    "m1": 0.5234602302310271, "m2": 0.6255677234174437, "l1": 0.2, "l2": 0.3, "r1": 0.2, "r2": 0.25569305436052964,
    "b1": 0.001, "b2": 0.001, "cf1": 0.16, "cf2": 0.12, "g": 9.81, "I1": 0.031887199591513114, "I2": 0.05086984812807257,
    "Ir": 6.287203962819607e-05, "gr": 6.0,
}  # fmt: skip

#: The four sets by model name, values of :data:`pendulab.model.robot.ROBOT_PARAM_NAMES`.
DFKI_C1: Mapping[str, Mapping[str, float]] = MappingProxyType(
    {
        "1.0": MappingProxyType(dict(_M10)),
        "1.1": MappingProxyType({**_M10, "Ir": 0.0, "b1": 0.0, "b2": 0.0, "cf1": 0.0, "cf2": 0.0}),
        "2.0": MappingProxyType({
            **_M10, "I1": 0.042111626356002546, "I2": 0.0510352807011669, "b1": 0.003690870343196907,
            "b2": 0.0006450852127932183, "cf1": 0.17467189894350432, "cf2": 0.10999997753612206,
            "m1": 0.7586436245588385, "m2": 0.33693688400430855, "r2": 0.4684380078598044,
        }),
        "3.0": MappingProxyType({
            **_M10, "I1": 0.03571133360368982, "I2": 0.010000000000000002, "Ir": 5.1336718481407864e-05,
            "b1": 0.049378979942464735, "b2": 0.020040916031588852, "cf1": 0.03314955511059797,
            "cf2": 0.03521137546780113, "m1": 0.874595478947918, "m2": 0.22041458616752638, "r2": 0.3267491550003389,
        }),
    }
)  # fmt: skip

#: What is known of C.1 without fitting: link lengths [m], gravity [m/s^2], gear ratio [-].
C1_GEOMETRY: Mapping[str, float] = MappingProxyType({"l1": 0.2, "l2": 0.3, "g": 9.81, "gr": 6.0})

_A0_M10 = {
    "m1": 0.608, "m2": 0.630, "l1": 0.3, "l2": 0.2, "r1": 0.275, "r2": 0.166, "b1": 0.081, "b2": 0.0, "cf1": 0.093,
    "cf2": 0.186, "g": 9.81, "I1": 0.05472, "I2": 0.02522, "Ir": 0.000060719, "gr": 6.0,
}  # fmt: skip

_A0_M20 = {
    "m1": 0.5593806151425046, "m2": 0.6043459469186889, "l1": 0.3, "l2": 0.2, "r1": 0.3, "r2": 0.18377686083653508,
    "b1": 0.001, "b2": 0.001, "cf1": 0.093, "cf2": 0.078, "g": 9.81, "I1": 0.053470810264216295,
    "I2": 0.02392374528789766, "Ir": 7.659297952841183e-05, "gr": 6.0,
}  # fmt: skip

#: A.0's three sets by model name, values of :data:`pendulab.model.robot.ROBOT_PARAM_NAMES`.
DFKI_A0: Mapping[str, Mapping[str, float]] = MappingProxyType(
    {
        "1.0": MappingProxyType(dict(_A0_M10)),
        "2.0": MappingProxyType(dict(_A0_M20)),
        "2.1": MappingProxyType({**_A0_M20, "Ir": 0.0, "b1": 0.0, "b2": 0.0, "cf1": 0.0, "cf2": 0.0}),
    }
)

#: What is known of A.0 without fitting: link lengths [m], gravity [m/s^2], gear ratio [-].
A0_GEOMETRY: Mapping[str, float] = MappingProxyType({"l1": 0.3, "l2": 0.2, "g": 9.81, "gr": 6.0})
