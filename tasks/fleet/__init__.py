"""Monte Carlo batches of way-point missions on the manoeuvring model (issue 27, check 2):
``fleet/survey``. Importing registers it.

Why a family of its own, not a batch mode of ``mission/survey``: every ``mission/`` name is one
vehicle (or a team) flown by MuJoCo through :class:`tasks.closed_loop.world.MissionWorld`, with
its gym environment, recording and per-tick run data; a fleet is a thousand vehicles on the
manoeuvring model (:mod:`bauv_sim.manoeuvring`) stepped together by array operations, with
per-run outcomes and decimated tracks, which none of those contracts fits.
"""

from tasks.fleet import survey

__all__ = ["survey"]
