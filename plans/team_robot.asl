// A robot of a team: it does its own task (faulty.asl: goToDestination, and its diagnosis when that
// fails) and helps the others when it is free (helper.asl). faultmas run --robots N --faulty K uses it.
{ include("faulty.asl") }
{ include("helper.asl") }
