// A single robot tries to reach its destination and, when the motion fails, looks at its own
// sensors (diagnoseAlone). The cooperative version (faulty.asl / helper.asl) extends this.
// Percepts (robot_bridge/percepts.py): odom(X, Y, YawDeg), encoders(L, R), moving, stopped, ...

destination(1.0).

!goToDestination.

+!goToDestination : destination(D)
   <- .print("going to my destination, ", D, " m ahead");
      move(D);
      ?odom(X, Y, _);
      .print("arrived: odometry says x=", X, " y=", Y).

-!goToDestination[error(action_failed), reason(R)]
   <- .print("fault detected: the motion failed (", R, ")");
      !diagnoseAlone(R).

+!diagnoseAlone(no_progress) : encoders(L, R)
   <- .print("my encoders read ", L, " and ", R, " ticks: they report no motion");
      .print("alone I cannot tell an encoder fault from dead actuators or stuck wheels: I need a helper").

+!diagnoseAlone(Reason)
   <- .print("unexplained failure (", Reason, "): I need a helper").
