"""Terrain-relative navigation (issue 23): matching seabed soundings against a bathymetry map.

* :mod:`nav.trn.map`: the navigator's map (:class:`TerrainMap`: bilinear depth and gradient,
  NaN cells and off-map points flagged) and :func:`degraded` (the map is never the truth);
* :mod:`nav.trn.soundings`: DVL beams, an altimeter or a multibeam, with the measured attitude,
  the lever arm and the pressure depth -> seabed soundings;
* :mod:`nav.trn.likelihood`: the likelihood with a common per-ping bias marginalised, the
  normalised innovation and the windowed divergence test;
* :mod:`nav.trn.particle`: :class:`ParticleTrn`; :mod:`nav.trn.point_mass`:
  :class:`PointMassTrn` (the same methods);
* :mod:`nav.trn.pcrb`: the posterior Cramer-Rao bound from the terrain's gradients;
* :mod:`nav.trn.dvl_aided`: :class:`DvlAidedTrn`, DR on the DVL and the filters on one clock
  (prediction at every ping, an update every period).

Learned from MB-System's ``mbtrnav`` (MBARI; innovation-based weighting, windowed NIS,
re-initialisation) and from Bergman (1999) and Anonsen & Hallingstad (2006); written here.
"""

from nav.trn.dvl_aided import DvlAidedOptions, DvlAidedTrn
from nav.trn.likelihood import DivergenceWindow, innovation_nis, log_likelihood
from nav.trn.map import TerrainMap, degraded
from nav.trn.options import TrnOptions, TrnUpdate
from nav.trn.particle import ParticleTrn, systematic_resample
from nav.trn.pcrb import terrain_information, trn_pcrb
from nav.trn.point_mass import PointMassTrn
from nav.trn.soundings import Soundings, soundings

__all__ = [
    "DivergenceWindow",
    "DvlAidedOptions",
    "DvlAidedTrn",
    "ParticleTrn",
    "PointMassTrn",
    "Soundings",
    "TerrainMap",
    "TrnOptions",
    "TrnUpdate",
    "degraded",
    "innovation_nis",
    "log_likelihood",
    "soundings",
    "systematic_resample",
    "terrain_information",
    "trn_pcrb",
]
