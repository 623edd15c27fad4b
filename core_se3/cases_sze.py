"""Placeholder: filled by its feature (registers cases into core_se3.cases.CASES)."""
