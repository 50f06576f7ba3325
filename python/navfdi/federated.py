"""Former home of the run result types, kept so that ``navfdi.federated`` imports keep working;
the types serve every architecture and live in :mod:`navfdi.runs`."""

from navfdi.runs import ERROR_COLUMNS, FaultMatch, ScenarioRun, VariantRuns, run_scenario

__all__ = ["ERROR_COLUMNS", "FaultMatch", "ScenarioRun", "VariantRuns", "run_scenario"]
