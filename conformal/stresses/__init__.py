"""Subsurface stresses and rolling-contact-fatigue indices (issue 24)."""
