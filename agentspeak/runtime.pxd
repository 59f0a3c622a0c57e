# C type of LocalRuntime for the compiled build (see intentions.pxd): its loop reads the agents' fields
# as structs. The fields set in __init__ are declared; a __dict__ keeps room for hooks that bridges add.
cimport cython
from agentspeak.agent cimport Agent
from agentspeak.communication cimport Message

cdef class LocalRuntime:
    cdef dict __dict__
    cdef public object agents, ready, _timed, _ready_set, _cond, _sleepers, _stop_at, _loop_thread, stopped, exit_code
    cdef public object printer, environment, trusted_senders, remote, undeliverable, source_dirs, _yield_turn, _yield_to
    cdef public object busy, directory, _urgent_in_row, _urgent

    @cython.locals(agent=Agent, woken_turns=int)
    cpdef _run(self, timeout, stop_when_idle)

    @cython.locals(target=Agent)
    cpdef _route_from(self, sender, Message message)
