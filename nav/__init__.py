"""nav: the navigation stack (estimators, models, accuracy, guidance, metrics).

Knows nothing of MuJoCo or of :mod:`bauv_sim`: it sees measurements, never truth. Arrays carry a
leading axis of Monte Carlo runs: state ``(n, dim)``, covariance ``(n, dim, dim)``.
"""

from nav._exports import lazy_exports
from nav.errors import NavError as NavError

_EXPORTS: dict[str, tuple[str, str]] = {
    "BatchEKF": ("nav.ekf", "BatchEKF"),
    "BeamGeometry": ("nav.seabed", "BeamGeometry"),
    "BearingMeasurement": ("nav.models", "BearingMeasurement"),
    "BroadcastRangeNavigator": ("nav.navigator", "BroadcastRangeNavigator"),
    "CmnfGains": ("nav.cmnf", "CmnfGains"),
    "ControlLimits": ("nav.local_control", "ControlLimits"),
    "CorrectedDeadReckoning": ("nav.drns", "CorrectedDeadReckoning"),
    "CourseSpeedDepthMotion": ("nav.models", "CourseSpeedDepthMotion"),
    "CurrentAwareMotion": ("nav.models", "CurrentAwareMotion"),
    "CurrentResponse": ("nav.correction", "CurrentResponse"),
    "DeadReckoning": ("nav.dead_reckoning", "DeadReckoning"),
    "DepthMeasurement": ("nav.models", "DepthMeasurement"),
    "Estimate": ("nav.navigator", "Estimate"),
    "Estimator": ("nav.ekf", "Estimator"),
    "FilterDivergedError": ("nav.errors", "FilterDivergedError"),
    "FollowerOptions": ("nav.navigator", "FollowerOptions"),
    "FollowerReport": ("nav.navigator", "FollowerReport"),
    "GuidanceCommand": ("nav.guidance", "GuidanceCommand"),
    "Histogram": ("nav.metrics", "Histogram"),
    "HorizontalPositionMeasurement": ("nav.models", "HorizontalPositionMeasurement"),
    "Measurement": ("nav.navigator", "Measurement"),
    "MeasurementModel": ("nav.ekf", "MeasurementModel"),
    "MotionModel": ("nav.ekf", "MotionModel"),
    "NavInputError": ("nav.errors", "NavInputError"),
    "Navigator": ("nav.navigator", "Navigator"),
    "OnlineNavigator": ("nav.navigator", "OnlineNavigator"),
    "PredictedShift": ("nav.bearings", "PredictedShift"),
    "Prediction": ("nav.bearings", "Prediction"),
    "SeriesSum": ("nav.metrics", "SeriesSum"),
    "ShiftEstimate": ("nav.seabed", "ShiftEstimate"),
    "SingleRunEKF": ("nav.ekf", "SingleRunEKF"),
    "SlantRangeMeasurement": ("nav.models", "SlantRangeMeasurement"),
    "SlopeBasis": ("nav.seabed", "SlopeBasis"),
    "SystemPrediction": ("nav.bearings", "SystemPrediction"),
    "UpdateInfo": ("nav.ekf", "UpdateInfo"),
    "UsblMeasurement": ("nav.models", "UsblMeasurement"),
    "Waypoint": ("nav.guidance", "Waypoint"),
    "WaypointGuidance": ("nav.guidance", "WaypointGuidance"),
    "baseline": ("nav.correction", "baseline"),
    "bearing_ekf_update": ("nav.bearings", "ekf_update"),
    "compensated_course": ("nav.correction", "compensated_course"),
    "cp1": ("nav.correction", "cp1"),
    "cp2": ("nav.correction", "cp2"),
    "dead_reckon": ("nav.dead_reckoning", "dead_reckon"),
    "direct_course": ("nav.guidance", "direct_course"),
    "distance_3d": ("nav.metrics", "distance_3d"),
    "first_exceedance": ("nav.metrics", "first_exceedance"),
    "gate_limit": ("nav.ekf", "gate_limit"),
    "horizontal_distance": ("nav.metrics", "horizontal_distance"),
    "limited_control": ("nav.local_control", "limited_control"),
    "nees": ("nav.metrics", "nees"),
    "nees_band": ("nav.metrics", "nees_band"),
    "optimal_control": ("nav.local_control", "optimal_control"),
    "pcrb": ("nav.pcrb", "pcrb"),
    "seabed_track": ("nav.seabed", "seabed_track"),
    "series_stats": ("nav.metrics", "series_stats"),
    "shift_estimate": ("nav.seabed", "shift_estimate"),
    "train_cmnf": ("nav.cmnf", "train"),
    "upmf_update": ("nav.bearings", "upmf_update"),
}
"""Public name -> (module, attribute), imported on first use."""

__all__, __getattr__, __dir__ = lazy_exports(globals(), _EXPORTS, eager=("NavError",))
