"""Layer 8b, control: equilibria at control rates.  A :class:`Session` holds an equilibrium and
the factorisation of its tangent and moves it warm to new commands -- the load factor and the
design layer's variables (field components, magnetisation per region, load magnitudes) -- by a
sensitivity predictor and modified-Newton corrector iterations on the held factors
(``control.corrector``), splitting or refusing a command that leaves the equilibrium path;
:meth:`Session.jacobian` gives the design layer's sensitivities at the current state on the
same factors.  ``control.loop`` closes the loop: Jacobian feedback tracking a target trajectory
(:func:`track`) and a command trajectory planned as a sequence of warm-started inverse problems
(:func:`plan`).  See docs/CONTROL.md.

Example
-------
>>> from core_se3 import control
>>> "Session" in control.__all__ and "track" in control.__all__
True
"""
from .commands import Commands, scenario_variables
from .corrector import Corrector, SubStep
from .loop import Feedback, Plan, PlanOptions, Tracking, plan, track
from .options import ControlOptions
from .session import Session, State, Work

__all__ = ["Session", "State", "Work", "ControlOptions", "Commands", "scenario_variables", "Corrector", "SubStep",
           "track", "plan", "Feedback", "PlanOptions", "Tracking", "Plan"]
