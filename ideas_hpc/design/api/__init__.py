"""One way to call a designer (issue 30): a problem, a frozen settings object,
:func:`minimize`, one :class:`DesignResult`.

As in pymoo, the three are apart: the *problem* is what is searched (the
candidate bank, its stereo scorer, the scenario bank, or a GA's batch
evaluator), the *settings* are the designer's knobs (a frozen dataclass with
unit-suffixed fields) and :func:`minimize` picks the one registered designer
that takes both (:data:`DESIGNERS`). A new designer is one
:func:`register` call with its settings class; the campaign layer builds the
settings from the file and never names a designer.
"""

from ideas_hpc.design.api.result import (DESIGNERS, DesignResult, Designer, designer_for,
                                         minimize, register)
from ideas_hpc.design.api.designers import (CoverSettings, FovGAProblem, NadirGAProblem,
                                            ParetoSettings, ReliableSettings, ScenarioProblem)
from ideas_hpc.design.ga.settings import FovGASettings, GASearch, NadirGASettings

__all__ = ["DESIGNERS", "DesignResult", "Designer", "designer_for", "minimize", "register",
           "CoverSettings", "ReliableSettings", "ParetoSettings", "NadirGASettings",
           "FovGASettings", "GASearch", "ScenarioProblem", "NadirGAProblem", "FovGAProblem"]
