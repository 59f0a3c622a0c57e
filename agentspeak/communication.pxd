# C type of Message for the compiled build (see intentions.pxd): the same fields as its __slots__.
cdef class Message:
    cdef public object sender, receiver, performative, content, _msg_id, in_reply_to, sent_at, read_at

cimport cython
from agentspeak.intentions cimport Event
from agentspeak.program cimport Trigger

@cython.locals(trigger=Trigger, ev=Event)
cpdef receive_message(agent, Message msg, bint by_default=*)
