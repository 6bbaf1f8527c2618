"""A constraint written the way a user would write one: one file, one class, nothing else edited.

``EffortShare(share)`` keeps every reduced effort within ``share`` of its limit, ``SpeedShare``
every reduced velocity within ``share`` of its speed limit. Their sets can be computed a second
way, by scaling the robot's limits, which is what the tests compare against.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mobmanip.terms.constraints import Constraint, ConstraintRows, Terms


@dataclass(frozen=True)
class EffortShare(Constraint):
    """|tau_i| <= share * tau_max_i for every reduced effort."""

    share: float = 0.5
    name: str = "effort_share"
    problem: str = "acceleration"

    def rows(self, terms: Terms) -> ConstraintRows:
        n = len(terms.effort_limits)
        limit = self.share * terms.effort_limits
        labels = tuple(
            f"{joint} at {self.share:g} of its effort limit ({s})" for s in "+-" for joint in terms.reduced_names
        )
        return ConstraintRows(
            self.name, self.problem, G={"tau": np.vstack([np.eye(n), -np.eye(n)])}, h=np.r_[limit, limit], labels=labels
        )


@dataclass(frozen=True)
class SpeedShare(Constraint):
    """|x_i| <= share * xdot_max_i for every reduced velocity."""

    share: float = 0.5
    name: str = "speed_share"
    problem: str = "velocity"

    def rows(self, terms: Terms) -> ConstraintRows:
        n = len(terms.velocity_limits)
        limit = self.share * terms.velocity_limits
        return ConstraintRows(
            self.name, self.problem, G={"x": np.vstack([np.eye(n), -np.eye(n)])}, h=np.r_[limit, limit]
        )
