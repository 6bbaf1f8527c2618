"""Objectives on any registered measure, and their gradients by checked central differences.

The ellipsoids' measures have closed-form gradients (:mod:`mobmanip.gradients.evaluator`). Every
other registered measure (the capacity polytopes, the force measures, a measure a user
registers) is read the same way for every set: its *support* along a unit task direction d
(max over the set of d . p) or its *reach* from rest along d (how far the straight line from
the origin along d stays in the set). A :class:`ReadingObjective` names one such reading,
``MEASURE:READING:DIRECTION``, e.g. ``dynamic_polytope:reach:+x`` or ``force_polytope:support:-z``.

Its gradient (:class:`ReadingGradient`) is taken by central differences in Pinocchio's tangent
space: entry k is ``(f(q + h e_k) - f(q - h e_k)) / (2 h)`` with ``q + h e_k`` meaning
``pin.integrate(model, q, h e_k)``, as the analytic gradients are laid out, at the step
:data:`STEP`. The measures are computed to about 1e-9 of their size, so the step's round-off is
about 1e-4 of the gradient's scale, and the truncation error of the central difference
(O(h^2)) is far below that. A polytope's reading is the value of a linear program whose data
move with q: smooth between the configurations where its binding rows change, with a kink
there. The difference is therefore *checked*: the same difference at twice the step must agree
to :data:`SMOOTH_RTOL` of the larger of the gradient's largest entry and the reading itself,
else the configuration counts as a kink (:attr:`ReadingGradient.kinks`) and the difference at
the smaller step is taken: an average of the slopes on the two sides, which a climbing method
can follow where both slopes agree in sign.

A reading costs one measure at each of 4 nv + 1 configurations (two steps, both signs, every
tangent direction), about 1 ms each for the polytopes of the robots shipped here: about 0.1 s
per gradient on TIAGo++ (nv = 19).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import ArgumentError, MeasureError, UnknownMeasureError
from ..measures import MEASURES, get_measure
from ..robot.model import Robot
from ..robot.tasks import TaskSpace, get_task
from ..sets.taskset import TaskSet
from ..terms.builder import terms_at
from .evaluator import ELLIPSOIDS, GradientEvaluator, Objective

#: The readings of a set an objective may name.
READINGS = ("reach", "support")
#: Central-difference step along each tangent direction (m or rad).
STEP = 1e-5
#: The differences at STEP and 2 STEP agree to this share of the gradient's scale where the
#: reading is smooth.
SMOOTH_RTOL = 1e-3


@dataclass(frozen=True)
class ReadingObjective:
    """``MEASURE:READING:DIRECTION``: the ``reach`` (from rest, along the straight line) or the
    ``support`` (extent with the other components free) of a registered measure's set along a
    unit task direction.

    Attributes:
        measure: the registered measure's name.
        reading: ``"reach"`` or ``"support"``.
        direction: unit task direction, (m,).
        text: what it was parsed from.
        direction_text: the direction as written (``+x``).
    """

    measure: str
    reading: str
    direction: tuple[float, ...]
    text: str
    direction_text: str = ""

    @property
    def name(self) -> str:
        return self.text

    @property
    def measure_name(self) -> str:
        """The measure whose set is read (as :attr:`Objective.measure_name`)."""
        return self.measure

    @property
    def index(self) -> str:
        """The reading (as :attr:`Objective.index` names an ellipsoid's index)."""
        return self.reading

    #: A reading is of the whole set along its direction: no block of task rows.
    block = None
    rows = None

    @classmethod
    def parse(cls, text: str, task: str | TaskSpace) -> ReadingObjective:
        """From ``MEASURE:READING:DIRECTION`` (DIRECTION as :meth:`Objective.parse` reads it).

        Raises:
            ArgumentError: not three parts, an unknown reading, a bad direction.
            MeasureError: not a registered measure, or an ellipsoid whose objectives are
                :class:`Objective`'s.
        """
        task = get_task(task)
        parts = str(text).split(":")
        if len(parts) != 3:
            raise ArgumentError(
                f"a measure's reading is MEASURE:READING:DIRECTION (e.g. dynamic_polytope:reach:+x), got {text!r}"
            )
        measure, reading, direction = parts
        if measure in ELLIPSOIDS:
            raise MeasureError(
                f"objective {text!r}: the {measure} ellipsoid's objectives are {measure}:INDEX[:DIRECTION]"
            )
        if measure not in MEASURES:
            raise UnknownMeasureError(measure, MEASURES)
        if reading not in READINGS:
            raise ArgumentError(f"objective {text!r}: the reading must be one of {', '.join(READINGS)}")
        unit = Objective.parse(f"dynamic:capacity:{direction}", task)  # its direction, checked and made unit
        unit.check_task(task)
        assert unit.direction is not None
        return cls(measure, reading, unit.direction, str(text), direction.strip())

    def read(self, task_set: TaskSet) -> float:
        """The reading of one of the measure's sets (0 when the set is empty).

        Raises:
            MeasureError: ``reach`` of a set that has no straight-line reach.
        """
        if task_set.empty:
            return 0.0
        d = np.asarray(self.direction)
        if self.reading == "support":
            return float(task_set.support(d))
        reach = getattr(task_set, "straight_line_reach", None)
        if reach is None:
            raise MeasureError(f"{self.measure}'s sets have no straight-line reach: read their support instead")
        return float(reach(d))


def is_reading_objective(text: str) -> bool:
    """Whether ``text`` names a reading of a registered measure other than the two ellipsoids
    with closed-form gradients (``MEASURE:...``)."""
    head = str(text).split(":", 1)[0]
    return head in MEASURES and head not in ELLIPSOIDS


class ReadingGradient:
    """A reading's value and gradient at configurations of one robot, as
    :class:`~mobmanip.gradients.GradientEvaluator` gives an ellipsoid's (see the module's
    docstring for the method and its checks).

    Args:
        robot: the loaded robot.
        objective: a :class:`ReadingObjective` or its text.
        task: task space (default the spec's).
        object_mass: mass of the object held between the hands (kg); default the spec's.
        decoupled: the decoupled P (accelerations).
        constraints: constraints the measure's sets honour (the floor's, say); the sets of a
            measure that does not honour them are computed without.
        step: the central difference's step (> 0, at most 1e-2).
    """

    def __init__(
        self,
        robot: Robot,
        objective: ReadingObjective | str,
        task: str | TaskSpace | None = None,
        *,
        object_mass: float | None = None,
        decoupled: bool = False,
        constraints: tuple = (),
        step: float = STEP,
    ):
        self.task = get_task(task or robot.spec.default_task)
        self.objective = (
            objective if isinstance(objective, ReadingObjective) else ReadingObjective.parse(objective, self.task)
        )
        if len(self.objective.direction) != self.task.dim:
            raise ArgumentError(f"objective {self.objective.name!r}: its direction has {len(self.objective.direction)} "
                                f"components, task {self.task.name!r} has {self.task.dim}")  # fmt: skip
        if not (isinstance(step, (int, float)) and 0.0 < step <= 1e-2):
            raise ArgumentError(f"the difference step must be in (0, 0.01], got {step!r}")
        self.robot, self.object_mass, self.decoupled = robot, object_mass, decoupled
        self.constraints = tuple(constraints)
        self.measure = get_measure(self.objective.measure)
        self.step = float(step)
        #: Measures computed so far.
        self.evaluations = 0
        #: Gradients whose two differences disagreed (a kink of the reading).
        self.kinks = 0

    def task_set(self, q: np.ndarray) -> TaskSet:
        """The measure's set at q, (nq,) (checked by the caller)."""
        self.evaluations += 1
        terms = terms_at(self.robot, q, self.task.name, object_mass=self.object_mass, decoupled=self.decoupled,
                         constraints=self.constraints, check=False)  # fmt: skip
        return self.measure.compute(terms)

    def value(self, q: np.ndarray) -> float:
        """The reading at q, (nq,)."""
        return self.objective.read(self.task_set(self.robot.check_configuration(q)))

    def __call__(self, q: np.ndarray) -> tuple[float, np.ndarray, bool]:
        """(value, gradient (nv,), defined) at configuration q, (nq,): defined where the set is
        not empty and every reading is finite."""
        model = self.robot.model
        q = self.robot.check_configuration(q)
        here = self.task_set(q)
        f0 = self.objective.read(here)
        slopes = np.zeros((2, model.nv))
        basis = np.eye(model.nv)
        for i, h in enumerate((self.step, 2.0 * self.step)):
            for k in range(model.nv):
                up = self.objective.read(self.task_set(pin.integrate(model, q, h * basis[k])))
                down = self.objective.read(self.task_set(pin.integrate(model, q, -h * basis[k])))
                slopes[i, k] = (up - down) / (2.0 * h)
        grad = slopes[0]
        ok = bool(not here.empty and np.isfinite(f0) and np.all(np.isfinite(slopes)))
        scale = max(float(np.max(np.abs(slopes))), abs(f0), 1e-12)
        if ok and float(np.max(np.abs(slopes[0] - slopes[1]))) > SMOOTH_RTOL * scale:
            self.kinks += 1
        return f0, grad, ok


def objective_evaluator(
    robot: Robot,
    objective: Objective | ReadingObjective | str,
    task: str | TaskSpace | None = None,
    *,
    object_mass: float | None = None,
    decoupled: bool = False,
):
    """The evaluator of any objective: an ellipsoid's index by its closed-form gradient
    (:class:`~mobmanip.gradients.GradientEvaluator`), any other registered measure's reading by
    checked differences (:class:`ReadingGradient`). Both are called ``evaluator(q)`` for
    ``(value, gradient (nv,), defined)`` and carry ``objective`` and ``evaluations``."""
    if isinstance(objective, ReadingObjective) or (isinstance(objective, str) and is_reading_objective(objective)):
        return ReadingGradient(robot, objective, task, object_mass=object_mass, decoupled=decoupled)
    return GradientEvaluator(robot, objective, task, object_mass=object_mass, decoupled=decoupled)
