"""Closed loops on a control session (placeholder, written next)."""
__all__ = ["track", "plan", "Tracking", "Plan"]
track = plan = Tracking = Plan = None
