"""faultmas: diagnosis — consistency-based diagnosis (Reiter) and the rule engine that reacts to it.

Models (``load_model``): YAML system descriptions, the paper's software-architecture models, and
ISCAS-85 ``.bench`` netlists, all compiled to one ``SystemModel``. ``Diagnoser`` answers queries on one
persistent SAT solver per model; ``DiagnosisService`` runs them on worker threads for agents;
``RuleEngine`` fires rules on changes of observations and PosAb. CLI: ``faultmas diagnose``.
Imports are lazy so ``import diagnosis`` stays cheap (python-sat loads on first use).
"""
from __future__ import annotations


__all__ = ["load_model", "SystemModel", "Diagnoser", "DiagnosisResult", "DiagnosisService",
           "RuleEngine", "load_rules", "observation_of"]

_WHERE = {"load_model": "diagnosis.loader", "SystemModel": "diagnosis.model", "Diagnoser": "diagnosis.engine",
          "DiagnosisResult": "diagnosis.engine", "DiagnosisService": "diagnosis.service",
          "observation_of": "diagnosis.service", "RuleEngine": "diagnosis.rules", "load_rules": "diagnosis.rules"}


def __getattr__(name: str) -> object:
    if name in _WHERE:
        import importlib
        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'diagnosis' has no attribute {name!r}")
