"""Layer 9, the catalogue: benchmark cases (declarative data with registries of cases and case
families), the error measures every model of the project uses, the packaged reference data, and
the runner behind ``core-se3 bench``.

Example
-------
>>> from core_se3 import catalogue
>>> "cantilever-shear" in catalogue.CASES, catalogue.get_case("rollup").reference.entry
(True, '2_pure_bending_rollup_out_of_plane')
"""
from . import cases_contact, cases_design, cases_friction, cases_magnetic, cases_shells, cases_sze  # noqa: F401  (register the cases)
from . import family_contact, family_design, family_friction, family_magnetic, family_sze  # noqa: F401  (register the families)
from .case import (CASES, FAMILIES, Case, CaseLoad, Family, Reference, ResolvedLoad, Variant, add_case,
                   beam_EI, case_params, family_of, get_case, list_cases, register_family, resolve)
from .finite_bending import drilling_for_rotation, finite_bending_moment, limit_moment
from .generic import case_document, edge_wrench, planar, reference_for, torsion_constant
from .measures import (error_against_reference, interp_reference, lifted_length_from_gaps, path_distance,
                       point_curve_distances)
from .references import contact_lift_elastica, elastica_entry, elastica_names, literature_entry, literature_ids
from .run import build_problem, run_case

__all__ = ["Case", "CaseLoad", "Reference", "Variant", "ResolvedLoad", "CASES", "add_case", "get_case",
           "list_cases", "beam_EI", "Family", "FAMILIES", "register_family", "family_of",
           "case_params", "resolve", "build_problem", "run_case", "case_document", "reference_for",
           "planar", "edge_wrench", "torsion_constant", "error_against_reference", "interp_reference",
           "path_distance", "point_curve_distances", "elastica_entry", "elastica_names",
           "literature_entry", "literature_ids", "lifted_length_from_gaps", "contact_lift_elastica",
           "finite_bending_moment", "limit_moment", "drilling_for_rotation"]
