"""The platform in real time (docs/guide/realtime.md): what a scene's stream carries and how a
live input drives it (`live`), the margins its motion envelope needs, measured (`margins`), and the
live view in the browser (`view`). The envelope and its guard are the run's
(cosim.platform.run.envelope, .guard); the generic part, the pacing, the datagrams and the sockets,
is cosim.engine.realtime."""

from ..run.envelope import GUARD_KINDS, Envelope, check_reference, within
from ..run.guard import guarded_plan, reference_guard
from .live import LEG_OUTPUTS, check_scene_reference, real_time_plan, stream_fields, stream_names

__all__ = ["GUARD_KINDS", "Envelope", "check_reference", "within", "LEG_OUTPUTS", "check_scene_reference",
           "guarded_plan", "reference_guard", "real_time_plan", "stream_fields", "stream_names"]
