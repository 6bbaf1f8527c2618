"""A constraint written the way a user would write one: one file, nothing else edited.

``EffortShare(share)`` keeps every reduced effort within ``share`` of its limit, ``SpeedShare``
every reduced velocity within ``share`` of its velocity limit. Their sets can be computed a second
way, by scaling the robot's limits, which is what the tests compare against. Both are one
``Share`` of a kind of limit: the base class writes the rows, each subclass says which.
``ObjectAccelerationCap`` bounds the object's acceleration: a constraint of the sets at rest that
the commands over steps of motion must refuse.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from mobmanip.terms.constraints import Constraint, ConstraintRows, Terms


@dataclass(frozen=True)
class Share(Constraint):
    """|v_i| <= share * limit_i for every reduced value v of the problem's variable: the rows
    [I; -I] v <= [bound; bound], each labelled by its joint and side. A subclass names the
    variable, the robot's limits and what they limit (an effort limit by default)."""

    share: float = 0.5

    #: The problem's variable it bounds ("tau": the reduced efforts, "x": the reduced velocities).
    variable: ClassVar[str] = "tau"
    #: What the variable's limits are called: ``terms.<limit>_limits`` holds them.
    limit: ClassVar[str] = "effort"

    def rows(self, terms: Terms) -> ConstraintRows:
        bound = self.share * getattr(terms, f"{self.limit}_limits")
        n = len(bound)
        labels = tuple(
            f"{joint} at {self.share:g} of its {self.limit} limit ({s})" for s in "+-" for joint in terms.reduced_names
        )
        G = {self.variable: np.vstack([np.eye(n), -np.eye(n)])}
        return ConstraintRows(self.name, self.problem, G=G, h=np.r_[bound, bound], labels=labels)


@dataclass(frozen=True)
class EffortShare(Share):
    """|tau_i| <= share * tau_max_i for every reduced effort."""

    name: str = "effort_share"
    problem: str = "acceleration"


@dataclass(frozen=True)
class SpeedShare(Share):
    """|x_i| <= share * xdot_max_i for every reduced velocity."""

    name: str = "speed_share"
    problem: str = "velocity"
    variable: ClassVar[str] = "x"
    limit: ClassVar[str] = "velocity"


@dataclass(frozen=True)
class ObjectAccelerationCap(Constraint):
    """a_k <= 10 for every task component of the object's acceleration: rows of the sets at rest
    only (a step of motion or a replay of constant efforts cannot keep them)."""

    name: str = "object_acceleration_cap"
    problem: str = "acceleration"

    def rows(self, terms: Terms) -> ConstraintRows:
        m = terms.W.shape[0]
        labels = tuple(f"object acceleration {k} at most 10" for k in range(m))
        return ConstraintRows(self.name, self.problem, G={"a": np.eye(m)}, h=np.full(m, 10.0), labels=labels)
