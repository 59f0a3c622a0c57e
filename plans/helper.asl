// Cooperative fault diagnosis: the side of a robot that helps another one find out what is wrong.
//
// helpMe(F, at(X, Y)) -> canHelp (the first to answer is chosen; see faulty.asl) -> findRobot: go near
// where F said it is (the team's shared frame, see team_pose), then turn in steps until
// the robot's two cylinders are seen, then centre them; after a full turn without them, step back and
// look again from there (it may be too close for the depth camera); once found, keep a distance the
// camera measures well -> trackMe: where it is now -> giveMeFeedback: where it is after its test
// motion (re-finding it when sight was lost) -> thanks (or noThanks): turn back to my own task.
// Positions are reported in my odometry frame: seen(BearingDeg, DepthM, HeadingDeg).
//
// Percepts (robot_bridge/percepts.py): robot_seen(Name, AngleDeg, DepthM, YawDeg), odom(X,Y,YawDeg),
// camera_failed(Part),
// agent_alive(Name) (agents/zenoh_arch.py).

{ include("geometry.asl") }

search_step(40).         // degrees per look: the camera sees 57 degrees, so views overlap
look_wait(300).          // ms for fresh camera frames after a turn
centre_tolerance(4).     // degrees off the image centre that count as centred
centre_tries(4).
approach_stop(1.6).      // metres short of where the robot asking for help says it is
step_away(0.7).          // metres to step aside before a second search (see lookFromElsewhere)
near_limit(1.0, 1.4).    // metres: a robot found closer than the first may drive out of the depth
                         // range during its test motion: I back off to the second
far_limit(3.2, 2.6).     // metres: farther than the first, its cylinders are small: I come to the second

// A robot whose camera has failed (camera_failed(Part): its detector failed on every frame for a while)
// cannot look for anyone: it does not offer help, and a search under way ends, not found.
available :- not helping(_) & not on_mission & not diagnosing & not self_suspect & not camera_failed(_).

// ---- being asked ------------------------------------------------------------------------------
+!helpMe(F, At)[source(F)] : available & odom(_, _, Yaw)
   <- +helping(F); -+home_yaw(Yaw); -+help_at(F, At);
      .print(F, " needs help: I offer mine");
      .send(F, tell, canHelp).
+!helpMe(F, _)[source(F)] : camera_failed(Part) <- .print(F, " needs help, but my camera's ", Part, " has failed").
+!helpMe(F, _)[source(F)] <- .print(F, " needs help, but I am busy").
-!helpMe(F, _)[error(receiver_not_found)] : helping(F) <- .print(F, " is gone"); !release(F).

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
      .abolish(stepped(F));
      .abolish(help_at(F, _));
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
      !goNear(F, 2);
      !search(F, 0);
      !lookFromElsewhere(F);
      !keepDistance(F);
      !searchResult(F, Result).
+?findRobot(F, not_helping).

+!search(F, _) : camera_failed(Part) <- .print("my camera's ", Part, " has failed: I cannot see ", F).
+!search(F, _) : robot_seen(F, _, _, _) <- !centre(F, 0).
+!search(F, Turned) : Turned >= 360.
+!search(F, Turned) : search_step(S) & look_wait(W)
   <- turn(S);
      .wait(W);
      !search(F, Turned + S).
-!search(F, _).          // a turn failed (timed out, blocked): this search is over

+!centre(F, _) : robot_seen(F, A, _, _) & abs(A, AA) & centre_tolerance(T) & AA <= T.
+!centre(F, N) : robot_seen(F, A, _, _) & centre_tries(Max) & N < Max & look_wait(W)
   <- turn(A);
      .wait(W);
      !centre(F, N + 1).
+!centre(F, _).          // lost it again, or close enough after the tries

// Go to where F said it is, stopping approach_stop metres short and facing it, so that its cylinders are
// in view at a depth the camera measures well. Someone in the way (the move fails): step aside and try
// again, at most Tries times; then the search starts from wherever I am.
+!goNear(F, _) : help_at(F, at(X, Y)) & team_pose(MX, MY, _) & approach_stop(S) &
                 (X - MX) * (X - MX) + (Y - MY) * (Y - MY) <= (S + 0.5) * (S + 0.5).    // near enough
+!goNear(F, Tries) : help_at(F, at(X, Y)) & team_pose(MX, MY, MYaw) & approach_stop(S) & look_wait(W) &
                     direction(X - MX, Y - MY, A) & norm(A - MYaw, T)
   <- .print(F, " says it is at (", X, ", ", Y, "): I go near it");
      turn(T);
      !approachTo(F, S, Tries);
      .wait(W).
+!goNear(F, _).          // it did not say where it is (or I do not know where I am): look from here

+!approachTo(F, S, _) : help_at(F, at(X, Y)) & team_pose(MX, MY, MYaw) & direction(X - MX, Y - MY, A) &
                        norm(A - MYaw, T)
   <- turn(T);           // my first turn may have drifted
      move(math.sqrt((X - MX) * (X - MX) + (Y - MY) * (Y - MY)) - S).
-!approachTo(F, S, Tries) : Tries > 0 <- !sidestep(90, 0.6); !goNear(F, Tries - 1).
-!approachTo(F, S, _).
-!goNear(F, _).          // a side step failed too: look from here

// Where to step when a full turn showed nothing: sideways, across my line of sight. The usual reason
// for a blind turn is a robot seen end-on (its two cylinders hide each other), often after a glimpse
// that left me facing it: stepping along my own axis would keep that view, a side step of 0.7 m changes
// it by about 30 degrees at 1-1.5 m. I do not know where the robot is, so the steps alternate sides and
// also move me out of the depth camera's blind range (closer than 0.8 m) when it is right next to me.
+!lookFromElsewhere(F) : robot_seen(F, _, _, _).
+!lookFromElsewhere(F) : step_away(M)
   <- .print("no sign of ", F, " from here: I step aside and look again");
      .count(stepped(F), N);
      +stepped(F);
      !stepAway(F, N, M);
      !search(F, 0).

+!stepAway(F, 0, M) <- !sidestep(90, M).
+!stepAway(F, N, M) : N mod 2 == 1 <- !sidestep(-90, 2 * M).
+!stepAway(F, _, M) <- !sidestep(90, 2 * M).
-!stepAway(F, _, _).     // a turn failed: look again from where I am

+!sidestep(A, M) <- turn(A); !stepOrBack(M); turn(-A).
+!stepOrBack(M) <- move(M).
-!stepOrBack(M) <- !stepInstead(-M).     // blocked that way: the other way instead
+!stepInstead(M) <- move(M).
-!stepInstead(M).

// the robot in front of me (centred): back off or come closer so that its test motion stays in range
+!keepDistance(F) : robot_seen(F, _, D, _) & near_limit(L, G) & D < L & look_wait(W)
   <- .print(F, " is only ", D, " m away: I back off");
      move(D - G);
      .wait(W);
      !centre(F, 0).
+!keepDistance(F) : robot_seen(F, _, D, _) & far_limit(L, G) & D > L & look_wait(W)
   <- .print(F, " is ", D, " m away: I come closer");
      move(D - G);
      .wait(W);
      !centre(F, 0).
+!keepDistance(F).
-!keepDistance(F) : look_wait(W) <- .wait(W); !centre(F, 0).    // blocked: stay where I am

+!searchResult(F, found) : robot_seen(F, A, D, _)
   <- .print("found ", F, " at ", D, " m, ", A, " degrees off centre");
      .progress(robot_found, F).
+!searchResult(F, not_found) <- .print("could not find ", F, " from two places").

// ---- tracking the test motion ------------------------------------------------------------------
+?trackMe(F, Seen) : helping(F) <- !keepDistance(F); !observe(F, Seen, 1).

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
