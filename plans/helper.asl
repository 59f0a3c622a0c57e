// Cooperative fault diagnosis: the side of a robot that helps another one find out what is wrong.
//
// helpMe -> canHelp (the first to answer is chosen; see faulty.asl) -> findRobot: turn in steps until
// the robot's two cylinders are seen, then centre them; give up after a full turn -> trackMe: where it
// is now -> giveMeFeedback: where it is after its test motion (re-finding it when sight was lost) ->
// thanks (or noThanks): turn back and return to my own task.
// Positions are reported in my odometry frame: seen(BearingDeg, DepthM, HeadingDeg).
//
// Percepts (robot_bridge/percepts.py): robot_seen(Name, AngleDeg, DepthM, YawDeg), odom(X,Y,YawDeg),
// agent_alive(Name) (agents/zenoh_arch.py).

{ include("geometry.asl") }

search_step(40).         // degrees per look: the camera sees 57 degrees, so views overlap
look_wait(300).          // ms for fresh camera frames after a turn
centre_tolerance(4).     // degrees off the image centre that count as centred
centre_tries(4).

available :- not helping(_) & not on_mission & not diagnosing & not self_suspect.

// ---- being asked ------------------------------------------------------------------------------
+!helpMe(F)[source(F)] : available & odom(_, _, Yaw)
   <- +helping(F); -+home_yaw(Yaw);
      .print(F, " needs help: I offer mine");
      .send(F, tell, canHelp).
+!helpMe(F)[source(F)] <- .print(F, " needs help, but I am busy").

+noThanks[source(F)] : helping(F) <- .print(F, " found another helper"); !release(F).
+thanks[source(F)] : helping(F) <- .print("glad I could help ", F); !release(F).

-agent_alive(F) : helping(F)
   <- .print(F, " is gone: back to my own task");
      .drop_desire(search(F, _));
      .drop_desire(centre(F, _));
      !release(F).

+!release(F)
   <- -helping(F);
      .progress(released, F);
      .abolish(noThanks[source(F)]);
      .abolish(thanks[source(F)]);
      !returnToTask.

+!returnToTask : home_yaw(H) & odom(_, _, Y) & norm(H - Y, T)
   <- -home_yaw(H);
      turn(T);
      .print("back to my own task").
+!returnToTask.
-!returnToTask.          // preempted: someone else asked for help meanwhile

// ---- findRobot: asked with askOne, answered when the search ends -------------------------------
+?findRobot(F, Result) : helping(F)
   <- .print("looking for ", F);
      .progress(searching, F);
      !search(F, 0);
      !searchResult(F, Result).
+?findRobot(F, not_helping).

+!search(F, _) : robot_seen(F, _, _, _) <- !centre(F, 0).
+!search(F, Turned) : Turned >= 360.
+!search(F, Turned) : search_step(S) & look_wait(W)
   <- turn(S);
      .wait(W);
      !search(F, Turned + S).

+!centre(F, _) : robot_seen(F, A, _, _) & abs(A, AA) & centre_tolerance(T) & AA <= T.
+!centre(F, N) : robot_seen(F, A, _, _) & centre_tries(Max) & N < Max & look_wait(W)
   <- turn(A);
      .wait(W);
      !centre(F, N + 1).
+!centre(F, _).          // lost it again, or close enough after the tries

+!searchResult(F, found) : robot_seen(F, A, D, _)
   <- .print("found ", F, " at ", D, " m, ", A, " degrees off centre");
      .progress(robot_found, F).
+!searchResult(F, not_found) <- .print("could not find ", F, " after a full turn").

// ---- tracking the test motion ------------------------------------------------------------------
+?trackMe(F, Seen) : helping(F) <- !observe(F, Seen, 1).

+?giveMeFeedback(F, Seen) : helping(F) & look_wait(W)
   <- .wait(W);              // frames taken after the robot stopped
      !observe(F, Seen, 1).

+!observe(F, seen(B, D, Heading), _) : robot_seen(F, A, D, Y) & odom(_, _, H) & norm(H + A, B) & norm(H + Y, Heading)
   <- .print(F, " is at bearing ", B, ", ", D, " m, heading ", Heading).
+!observe(F, Seen, Retries) : Retries > 0
   <- .print("lost sight of ", F, ": finding it again");
      .progress(lost_sight, F);
      !search(F, 0);
      !observe(F, Seen, Retries - 1).
+!observe(F, lost, 0).
