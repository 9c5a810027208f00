"""Learn the map while the robot works: the free decay after each ordinary move's stop
(:mod:`tvist.learn.decay`) refines the modal map (:mod:`tvist.learn.learner`)."""

from tvist.learn.decay import Decay, ModeObservation, observe_decay
from tvist.learn.learner import MapLearner, Observation, PayloadReport

__all__ = [
    "Decay",
    "MapLearner",
    "ModeObservation",
    "Observation",
    "PayloadReport",
    "observe_decay",
]
