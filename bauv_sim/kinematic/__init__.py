"""The seeds' idealised (kinematic) motion models, vectorised over Monte Carlo runs.

Used to repeat the papers' experiments exactly and for fast statistics; they produce the same
truth record as the physics world.
"""
