# C types for the compiled build (agentspeak/_speedups.py): Event, Frame, IntendedMeans and Intention
# become extension types whose fields compiled code reads as struct members (no dict or descriptor
# lookup). The same fields as each class's __slots__; a slot added there must be added here. From source
# this file is not read.
cdef class Event:
    cdef public object trigger, intention, handles

cdef class Frame:
    cdef public object body, kind, loop, solutions, reset
    cdef public object pc, index

cdef class IntendedMeans:
    cdef public object plan, b, frames, result, handles, event_literal, trigger_b

cdef class Intention:
    cdef public object id, stack, suspended, atomic, waiting, fork, dropped, branch
    cdef object __weakref__
