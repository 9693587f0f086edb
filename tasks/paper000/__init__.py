"""Seed 000 (Naus & Nowak 2016): ``paper-000/test-1..3`` (straight passage: DR, EKF with USBL,
USBL alone) and ``paper-000/accuracy`` (analytic USBL and DR accuracy). Importing registers them."""

from tasks.paper000 import accuracy, passage

__all__ = ["accuracy", "passage"]
