# C types for the compiled build (see intentions.pxd). Agent is an extension type with its hot fields
# declared (and a __dict__ for everything else, so users and bridges may still add attributes); the
# reasoning cycle's methods (and the hottest body formulas, body.pxd) are cpdef with typed locals, so they read
# intentions, intended means and frames as structs. A Python subclass may still override any of them.
cimport cython
from agentspeak.intentions cimport Event, Frame, IntendedMeans, Intention
from agentspeak.program cimport Trigger

cdef class Agent:
    cdef dict __dict__
    cdef public object name, arch, _arch_seen, _perceive, registry, tro, bb, plans, events, running
    cdef public object suspended, mailbox, feedback, timers, event_waiters, condition_waiters
    cdef public object pending_futures, pending_asks, atomic_intention, percepts, source_file, stopped
    cdef public object cycles, failures_unhandled, dropped, current_intention, sleeping_evt, timer_lag, clock
    cdef public object timer_seen, timer_busy

    cpdef cycle(self)

    @cython.locals(ev=Event, trigger=Trigger, intention=Intention, f=Frame, im=IntendedMeans, new=Intention)
    cpdef deliberate(self)

    @cython.locals(intention=Intention, im=IntendedMeans, frame=Frame, top=IntendedMeans, f0=Frame)
    cpdef act(self)

    @cython.locals(trigger=Trigger, intention=Intention, top=IntendedMeans, f0=Frame)
    cpdef push_im(self, Event ev, plan, b)
