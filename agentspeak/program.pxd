# C type of Trigger for the compiled build (see intentions.pxd): the same fields as its __slots__.
cdef class Trigger:
    cdef public object op, kind, literal
