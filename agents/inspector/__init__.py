"""``faultmas inspect``: a live local web view of a running team (Jason's mind inspector, for a MAS).

Agent side (``publisher``): every agent of ``faultmas agent run`` answers a Zenoh query for its state
and, only while someone subscribes, streams it as it changes; an unwatched agent pays nothing per
reasoning cycle. Viewer side (``hub`` + ``web``): one Zenoh session gathers the team (presence, state,
robots' percepts, ``.progress`` steps) and a Starlette app serves the static page with server-sent
events. Key expressions are in ``keys``; the JSON a mind is described with in ``snapshot``; pause and
step in ``pause``; the observers' state in ``observers``; ``faultmas inspect`` in ``cli`` and
``faultmas run --inspect`` in ``live``. See docs/inspector.md.
"""

TIMELINE_MARKS = 10_000
"""Timeline marks the viewer keeps by default, the newest (``hub``; ``--timeline-marks``): ~500 bytes each, so
~5 MB (tracemalloc); a diagnosis makes ~30, so days of a team's reports at a few a minute, and more than a page
draws readably. Here, not in ``hub``, so that the command line's ``--help`` does not import the hub."""
