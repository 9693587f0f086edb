# The public names of nav.navigator, read by type checkers and by lazy_loader.attach_stub in
# __init__.py, which imports each from its module on first use (`name as name`: re-exported).

from .batch import BatchNavigator as BatchNavigator
from .follower import (
    BroadcastRangeNavigator as BroadcastRangeNavigator,
    FollowerOptions as FollowerOptions,
    FollowerReport as FollowerReport,
    LeaderState as LeaderState,
    RangeFixResult as RangeFixResult,
)
from .online import (
    Estimate as Estimate,
    Measurement as Measurement,
    Navigator as Navigator,
    OnlineNavigator as OnlineNavigator,
)
