"""The OpenXR session lifecycle (spec chapter "Session Lifecycle"), without pyopenxr.

The runtime drives XrSessionState through XrEventDataSessionStateChanged; the application must
answer some states with calls. `SessionLifecycle.on_state_changed()` returns the call due:

    READY          -> BEGIN    xrBeginSession, then run the frame loop
    SYNCHRONIZED / VISIBLE / FOCUSED -> nothing (keep running frames; render when shouldRender)
    STOPPING       -> END      xrEndSession (stop calling xrWaitFrame)
    EXITING        -> EXIT     destroy the session; the user or runtime asked to quit
    LOSS_PENDING   -> RECOVER  destroy the session; a new one may be created when the system
                               is available again (xrGetSystem succeeds)
    IDLE           -> nothing  (after END: wait for READY again or EXITING)
"""
from __future__ import annotations

import enum

from ..errors import XrError


class SessionState(enum.IntEnum):
    """XrSessionState, with the specification's values."""

    UNKNOWN = 0
    IDLE = 1
    READY = 2
    SYNCHRONIZED = 3
    VISIBLE = 4
    FOCUSED = 5
    STOPPING = 6
    LOSS_PENDING = 7
    EXITING = 8


class Action(enum.Enum):
    """The call the application owes the runtime after a state change."""

    NONE = "none"
    BEGIN = "begin"        # call xrBeginSession
    END = "end"            # call xrEndSession
    EXIT = "exit"          # destroy the session and stop
    RECOVER = "recover"    # destroy the session, then try to create a new one


# The transitions the specification's lifecycle diagram allows (from -> to).
ALLOWED = {
    SessionState.UNKNOWN: {SessionState.IDLE},
    SessionState.IDLE: {SessionState.READY, SessionState.EXITING, SessionState.LOSS_PENDING},
    SessionState.READY: {SessionState.SYNCHRONIZED, SessionState.STOPPING, SessionState.LOSS_PENDING},
    SessionState.SYNCHRONIZED: {SessionState.VISIBLE, SessionState.STOPPING, SessionState.LOSS_PENDING},
    SessionState.VISIBLE: {SessionState.FOCUSED, SessionState.SYNCHRONIZED, SessionState.LOSS_PENDING},
    SessionState.FOCUSED: {SessionState.VISIBLE, SessionState.LOSS_PENDING},
    SessionState.STOPPING: {SessionState.IDLE, SessionState.LOSS_PENDING},
    SessionState.LOSS_PENDING: set(),
    SessionState.EXITING: set(),
}


class SessionLifecycle:
    """Tracks the session state and whether the frame loop may run.

    `running` is true between xrBeginSession and xrEndSession (or the session's end: EXITING,
    LOSS_PENDING): only then may xrWaitFrame, xrBeginFrame and xrEndFrame be called.
    `history` keeps every state seen, for tests and logs. Unexpected transitions are recorded
    in `anomalies` (the runtime is the authority: we follow it).
    """

    def __init__(self):
        self.state = SessionState.UNKNOWN
        self.running = False
        self.exit_requested = False
        self.exit_sent = False       # xrRequestExitSession was called
        self.history: list[SessionState] = [self.state]
        self.anomalies: list[tuple[SessionState, SessionState]] = []

    @property
    def ended(self) -> bool:
        """The session is gone (exiting or lost): no more frames from it."""
        return self.state in (SessionState.EXITING, SessionState.LOSS_PENDING)

    def on_state_changed(self, new_state: int) -> Action:
        """Record the runtime's new state; return the call the application owes it."""
        try:
            new = SessionState(int(new_state))
        except ValueError:
            raise XrError(f"OpenXR runtime reported an unknown session state {new_state}; "
                          f"update rayvr or the runtime") from None
        if new not in ALLOWED[self.state]:
            self.anomalies.append((self.state, new))
        self.state = new
        self.history.append(new)
        if self.ended:
            self.running = False   # no frame calls on a session that is exiting or lost
        if new == SessionState.READY:
            return Action.BEGIN
        if new == SessionState.STOPPING:
            return Action.END
        if new == SessionState.EXITING:
            return Action.EXIT
        if new == SessionState.LOSS_PENDING:
            return Action.RECOVER
        return Action.NONE

    def began(self) -> None:
        """xrBeginSession succeeded."""
        self.running = True

    def ended_session(self) -> None:
        """xrEndSession succeeded."""
        self.running = False

    def should_request_exit(self) -> bool:
        """The app wants to quit and the session still runs: call xrRequestExitSession."""
        return self.exit_requested and not self.exit_sent and self.running
