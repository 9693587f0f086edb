"""Cooperative navigation of a team on kinematic truth (issue 24)."""
