# C types for the compiled build of the body formulas (moved with them from agent.pxd, unchanged; see
# intentions.pxd). The hottest formulas are cpdef with the agent, intention, intended means and frame typed,
# so they read them as structs.
cimport cython
from agentspeak.agent cimport Agent
from agentspeak.intentions cimport Frame, IntendedMeans, Intention

cdef class IAContext:
    cdef public object agent, intention, im, b, trail

@cython.locals(ctx=IAContext)
cpdef _exec_internal(Agent ag, Intention intention, IntendedMeans im, Frame frame, instr)

cpdef _exec_constraint(Agent ag, Intention intention, IntendedMeans im, Frame frame, instr)
