# The public names of nav, read by type checkers and by lazy_loader.attach_stub in
# __init__.py, which imports each from its module on first use (`name as name`: re-exported).

from ._aliases import (
    bearing_ekf_update as bearing_ekf_update,
    degraded_map as degraded_map,
    filter_bank_step as filter_bank_step,
    train_cmnf as train_cmnf,
)
from .angles import rotation_world_from_body as rotation_world_from_body
from .bearings.bank import BankOptions as BankOptions
from .bearings.cmnf import CmnfGains as CmnfGains
from .bearings.filters import upmf_update as upmf_update
from .bearings.local_control import (
    ControlLimits as ControlLimits,
    limited_control as limited_control,
    optimal_control as optimal_control,
)
from .bearings.model import (
    BearingTangents as BearingTangents,
    PredictedShift as PredictedShift,
    Prediction as Prediction,
    SystemPrediction as SystemPrediction,
)
from .bearings.pcrb import pcrb as pcrb
from .cooperative import (
    ClockOptions as ClockOptions,
    CoopNavigator as CoopNavigator,
    CoopOptions as CoopOptions,
    OwttRangeMeasurement as OwttRangeMeasurement,
    PeerEstimate as PeerEstimate,
    team_metrics as team_metrics,
    team_tracks as team_tracks,
    TeamEkf as TeamEkf,
    TeamRecord as TeamRecord,
    TeamTracks as TeamTracks,
    TwttRangeMeasurement as TwttRangeMeasurement,
    VehicleMetrics as VehicleMetrics,
)
from .dead_reckoning import (
    dead_reckon as dead_reckon,
    DeadReckonedTrack as DeadReckonedTrack,
    DeadReckoning as DeadReckoning,
    track_with_covariance as track_with_covariance,
)
from .dvl import (
    dvl_increment_covariance as dvl_increment_covariance,
    dvl_increments as dvl_increments,
    dvl_track as dvl_track,
    DvlVelocityMeasurement as DvlVelocityMeasurement,
    GroundVelocityMotion as GroundVelocityMotion,
    velocity_world_from_dvl as velocity_world_from_dvl,
)
from .ekf import (
    BatchEKF as BatchEKF,
    Estimator as Estimator,
    gate_limit as gate_limit,
    MeasurementModel as MeasurementModel,
    MotionModel as MotionModel,
    SingleRunEKF as SingleRunEKF,
    UpdateInfo as UpdateInfo,
)
from .errors import (
    FilterDivergedError as FilterDivergedError,
    NavError as NavError,
    NavInputError as NavInputError,
)
from .guidance import (
    direct_course as direct_course,
    GuidanceCommand as GuidanceCommand,
    Waypoint as Waypoint,
    WaypointGuidance as WaypointGuidance,
)
from .guidance_batch import (
    BatchWaypointGuidance as BatchWaypointGuidance,
    horizontal_sigma_batch_m as horizontal_sigma_batch_m,
)
from .metrics import (
    distance_3d as distance_3d,
    first_exceedance as first_exceedance,
    Histogram as Histogram,
    horizontal_distance as horizontal_distance,
    nees as nees,
    nees_band as nees_band,
    series_stats as series_stats,
    SeriesSum as SeriesSum,
)
from .models import (
    BearingMeasurement as BearingMeasurement,
    CourseSpeedDepthMotion as CourseSpeedDepthMotion,
    CurrentAwareMotion as CurrentAwareMotion,
    DepthMeasurement as DepthMeasurement,
    HorizontalPositionMeasurement as HorizontalPositionMeasurement,
    SlantRangeMeasurement as SlantRangeMeasurement,
    UsblMeasurement as UsblMeasurement,
)
from .navigator import (
    BatchNavigator as BatchNavigator,
    BroadcastRangeNavigator as BroadcastRangeNavigator,
    Estimate as Estimate,
    FollowerOptions as FollowerOptions,
    FollowerReport as FollowerReport,
    Measurement as Measurement,
    Navigator as Navigator,
    OnlineNavigator as OnlineNavigator,
)
from .relative import (
    dr_track as dr_track,
    ekf_track as ekf_track,
    FollowerNavigator as FollowerNavigator,
    ga_fix as ga_fix,
    ga_track as ga_track,
    GaOptions as GaOptions,
    LeaderRanges as LeaderRanges,
    RangeEkfOptions as RangeEkfOptions,
)
from .seabed import (
    BeamGeometry as BeamGeometry,
    seabed_track as seabed_track,
    shift_estimate as shift_estimate,
    ShiftEstimate as ShiftEstimate,
    SlopeBasis as SlopeBasis,
)
from .surfacing import (
    baseline as baseline,
    compensated_course as compensated_course,
    CorrectedDeadReckoning as CorrectedDeadReckoning,
    cp1 as cp1,
    cp2 as cp2,
    CurrentResponse as CurrentResponse,
)
from .trn import (
    DvlAidedOptions as DvlAidedOptions,
    DvlAidedTrn as DvlAidedTrn,
    ParticleTrn as ParticleTrn,
    PointMassTrn as PointMassTrn,
    Soundings as Soundings,
    soundings as soundings,
    TerrainMap as TerrainMap,
    trn_pcrb as trn_pcrb,
    TrnOptions as TrnOptions,
    TrnUpdate as TrnUpdate,
)
