"""Real robots: an online :class:`Session` with a crash-safe log, its audit (Table IX) and fault replays.

Modules: ``log`` (append-only JSON Lines, fsync, one writer), ``session`` (the online
API), ``table`` (a log as audit rows; Table IX), ``replay`` (recorded probes under
another model or an injected fault) and ``simulated`` (a stand-in robot: the simulated
rig writing the same logs). See ``docs/robot.md``.
"""

from probecommit.robot.log import SessionLocked, SessionLogError
from probecommit.robot.session import Decision, Session, SessionError, load_session

__all__ = ["Decision", "Session", "SessionError", "SessionLocked", "SessionLogError", "load_session"]
