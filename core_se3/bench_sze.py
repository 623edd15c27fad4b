"""Placeholder: filled by its feature (registers a Family into core_se3.bench.FAMILIES)."""
