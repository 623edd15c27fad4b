"""Layer 5, results: the per-step records of a solve, the one step recorder, and the result
document (JSON schema v1) writer and reader.

Example
-------
>>> from core_se3 import results
>>> results.SCHEMA, results.VERSION
('core-se3-result', 1)
"""
from .document import (ROUNDOFF_NOTE, SCHEMA, VERSION, format_backends, format_residual, mesh_record, probe_record, read_json,
                       result_document, step_record, step_totals, timing_record, write_json)
from .recorder import StepRecorder, initial_state, lab_totals, reaction_owners, restore_multipliers, support_names
from .result import ProbeState, ProbeTable, Result, StepResult, UnknownProbeError, unwrap_rotation

__all__ = ["Result", "StepResult", "ProbeState", "ProbeTable", "UnknownProbeError", "unwrap_rotation", "StepRecorder", "lab_totals", "restore_multipliers",
           "initial_state", "support_names", "reaction_owners", "SCHEMA",
           "VERSION", "read_json", "write_json", "probe_record", "step_record", "format_residual", "format_backends", "ROUNDOFF_NOTE",
           "mesh_record",
           "timing_record", "step_totals", "result_document"]
