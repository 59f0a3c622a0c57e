// Cooperative fault diagnosis: the side of a robot that finds out something is wrong with itself.
//
// goToDestination -> on failure diagnoseAlone (own sensors + the model-based diagnoser) -> if the
// diagnosis is still ambiguous, broadcastHelp -> with the first helper that accepts: it finds me
// (findRobot; when it cannot, I turn to show it another side and it looks again), trackMe (I turn
// first when it sees me nearly end-on), tryMove (turned round when my bumper stops it), giveMeFeedback
// -> diagnose again with what the helper saw -> thanks. A weak wheel curls my first leg, so I may end
// anywhere near the helper, facing anywhere.
// The decision is the diagnoser's (.diagnose on plans/turtlebot_hardware.yaml); outcome/2 only names
// the minimal diagnosis it returns. Steps worth timing are reported with .progress (agents/progress.py).
//
// Percepts (robot_bridge/percepts.py): odom(X,Y,YawDeg), encoders(L,R), over_current(Wheel),
// agent_alive(Name) (agents/zenoh_arch.py). Beliefs a run may give: destination(Metres).

destination(1.0).
model(turtlebot_hardware).
test_move(0.15).            // metres driven while the helper watches
help_timeout(3000).         // ms to wait for a helper to accept, per round
help_rounds(4).             // rounds of asking (busy robots may become free) before giving up
find_timeout(90000).        // ms a helper may take to find me
answer_timeout(20000).      // ms for the other answers
max_trials(2).              // test motions with one helper before giving up on it
max_finds(3).               // times one helper may look for me; I turn between them to show another side
find_turn(70).              // degrees I turn for that
settle_wait(600).           // ms after a turn before the helper looks (the base slows down; with dead
                            // encoders a failed turn has still turned me, and odometry cannot tell)

outcome([], none).
outcome([left_encoder, right_encoder], encoders).
outcome([left_motor, right_motor], both_actuators).
outcome([left_wheel, right_wheel], stuck_wheels).      // the motors push (over-current), nothing turns
outcome([left_motor], left_actuator).
outcome([right_motor], right_actuator).

// ---- encoder arithmetic (16-bit wrapping counters) and what the robot's own sensors say
ticks(From, To, D) :- D = ((To - From) mod 65536 + 65536) mod 65536.
motion_obs(DL, DR, encoders_report_motion) :- DL + DR > 100.
motion_obs(DL, DR, ~encoders_report_motion) :- DL + DR <= 100.
straight_obs(DL, DR, encoders_report_straight) :- DL - DR <= 0.25 * (DL + DR) + 40 & DR - DL <= 0.25 * (DL + DR) + 40.
straight_obs(DL, DR, ~encoders_report_straight) :- not straight_obs(DL, DR, encoders_report_straight).
current_obs(left, left_over_current) :- saw_over_current(left).
current_obs(left, ~left_over_current) :- not saw_over_current(left).
current_obs(right, right_over_current) :- saw_over_current(right).
current_obs(right, ~right_over_current) :- not saw_over_current(right).

// ---- what the helper saw (its odometry frame: bearing and heading in degrees, depth in metres)
{ include("geometry.asl") }
helper_obs(seen(B1, D1, Y1), seen(B2, D2, Y2), [helper_found_robot, Motion, Straight, Left, Right]) :-
    norm(Y2 - Y1, Turn) & abs(Turn, AT) & abs(D2 - D1, DD) & norm(B2 - B1, DB) & abs(DB, AB) &
    (AT > 6 | DD > 0.04 | AB * 0.01745 * D1 > 0.04) & Motion = helper_saw_motion &
    (Turn > 10 & Left = helper_saw_veer_left | Turn <= 10 & Left = ~helper_saw_veer_left) &
    (Turn < -10 & Right = helper_saw_veer_right | Turn >= -10 & Right = ~helper_saw_veer_right) &
    (AT <= 10 & Straight = helper_saw_straight | AT > 10 & Straight = ~helper_saw_straight).
helper_obs(seen(B1, D1, Y1), seen(B2, D2, Y2),
           [helper_found_robot, ~helper_saw_motion, ~helper_saw_straight, ~helper_saw_veer_left, ~helper_saw_veer_right]).
helper_obs(_, _, []).    // the helper lost sight of me: it saw nothing that helps

// Degrees to turn in place so that a helper looking along bearing B sees my side (my heading Y in its
// frame): end-on, my two cylinders hide each other, and a test motion along its line of sight hardly
// moves me in its image. Side-on enough already: no turn.
side_turn(B, Y, T) :- norm(Y - B, A) & abs(A, AA) & aspect_turn(A, AA, T).
aspect_turn(_, AA, 0) :- AA >= 65 & AA <= 115.
aspect_turn(A, AA, T) :- (AA < 65 | AA > 115) & A >= 0 & T = 90 - A.
aspect_turn(A, AA, T) :- (AA < 65 | AA > 115) & A < 0 & T = -90 - A.

!goToDestination.

// ---- my own task ------------------------------------------------------------------------------
+!goToDestination : not encoders(_, _)           // the robot has not spoken yet
   <- .wait({+encoders(_, _)}, 10000);
      !goToDestination.
+!goToDestination : destination(D) & encoders(L, R)
   <- +on_mission;
      .print("going to my destination, ", D, " m ahead");
      .progress(started, D);
      -+leg_start(L, R);
      move(D);
      !checkArrival(D).

+!checkArrival(D) : odom(X, Y, _) & (X - D) * (X - D) + Y * Y < 0.01
   <- -on_mission;
      .print("arrived: odometry says x=", X, " y=", Y);
      .progress(arrived).
+!checkArrival(D) : odom(X, Y, _)
   <- .print("I should be at x=", D, " y=0 but odometry says x=", X, " y=", Y);
      !faultDetected(off_course).

-!goToDestination[error(action_failed), reason(R)] <- !faultDetected(R).
-!goToDestination[error(E)] <- !faultDetected(E).

+over_current(W) : not saw_over_current(W) <- +saw_over_current(W).

// ---- fault detected: what do my own sensors say? ------------------------------------------------
// a fault detected without a leg's start or an encoder reading (the agent frozen, or its robot silent) cannot
// be examined (!ownObservations needs both): it ends undiagnosed, named, not at the run's timeout
+!faultDetected(Why) : not (leg_start(_, _) & encoders(_, _))
   <- -on_mission;
      +diagnosing;
      +self_suspect;
      .print("fault detected (", Why, ") but no leg start or encoder reading: I cannot examine it");
      .progress(fault_detected, Why);
      !undiagnosed([], Why).
+!faultDetected(Why)
   <- -on_mission;
      +diagnosing;
      +self_suspect;          // a robot that found a fault in itself does not offer help any more
      .print("fault detected (", Why, ")");
      .progress(fault_detected, Why);
      !ownObservations(Obs);
      !diagnoseAlone(Obs).

+!ownObservations([commanded_forward, M, S, CL, CR]) : leg_start(L0, R0) & encoders(L1, R1)
   <- ?ticks(L0, L1, DL); ?ticks(R0, R1, DR);
      ?motion_obs(DL, DR, M); ?straight_obs(DL, DR, S);
      ?current_obs(left, CL); ?current_obs(right, CR);
      .print("my encoders counted ", DL, " and ", DR, " ticks").

+!diagnoseAlone(Obs) : model(Model)
   <- .diagnose(Model, Obs, Ds);
      .print("alone, the diagnoser explains ", Obs, " by ", Ds);
      !decideOrAsk(Ds, Obs).

+!decideOrAsk([D], _) <- !decide(D).
+!decideOrAsk(Ds, _) <- -+candidates(Ds); .progress(ambiguous, Ds); !broadcastHelp(Ds).

+!decide(D) : outcome(D, O)
   <- .print("diagnosis: ", O, " (faulty components: ", D, ")");
      -diagnosing;
      !trustMyselfAgain(D);
      .progress(diagnosed, O).
+!decide(D)
   <- .print("diagnosis: faulty components ", D);
      -diagnosing;
      .progress(diagnosed, D).

// nothing is wrong with me (a false alarm: held for a moment, or a motion slower than its bound): I may
// help the others again
+!trustMyselfAgain([]) <- -self_suspect.
+!trustMyselfAgain(_).

// ---- asking for help: the first helper that accepts (the others are released) --------------------
+!broadcastHelp(Ds) <- !askForHelp(Ds, 1).

// the help request says where I am (the team's shared frame), so that a helper far away comes near
where_i_am(at(X, Y)) :- team_pose(X, Y, _).
where_i_am(unknown) :- not team_pose(_, _, _).    // no start_pose: the helper looks from where it is

+!askForHelp(Ds, Round)
   <- .my_name(Me);
      ?where_i_am(At);
      .print("I cannot tell alone: asking for help");
      .progress(help_requested);
      .abolish(canHelp);
      .broadcast(achieve, helpMe(Me, At));
      !awaitHelper(Ds, Round).

+!awaitHelper(Ds, _) : canHelp[source(H)] & not tried(H) <- !withHelper(H, Ds).
+!awaitHelper(Ds, Round) : help_timeout(T) <- .wait({+canHelp[source(_)]}, T); !awaitHelper(Ds, Round).
-!awaitHelper(Ds, Round) : help_rounds(N) & Round < N <- !askForHelp(Ds, Round + 1).
-!awaitHelper(Ds, _) <- !undiagnosed(Ds, no_helper).

+canHelp[source(H)] : helper(Other) & Other \== H <- !courtesy(H, noThanks).

// a word to a helper that may be gone meanwhile (its process died or was killed): .send to an agent
// that does not exist fails, as in Jason (receiver_not_found), and there is nothing to say to it then
+!courtesy(H, Word) <- .send(H, tell, Word).
-!courtesy(_, _)[error(receiver_not_found)].

+!withHelper(H, Ds)
   <- +tried(H); -+helper(H);
      .findall(O, canHelp[source(O)] & O \== H, Others);
      for (.member(O, Others)) { !courtesy(O, noThanks) };
      .print(H, " will help me");
      .progress(helper_found, H);
      -+finds(H, 0);
      !findMe(H, Ds).

// ---- being found: the helper searches; if it cannot see me, I turn to show another side ---------
+!findMe(H, Ds) : finds(H, N) & max_finds(Max) & N >= Max
   <- .print(H, " could not find me (", N, " tries)"); !nextHelper(H, Ds).
+!findMe(H, Ds) : finds(H, N) & find_timeout(FT)
   <- -+finds(H, N + 1);
      !showAnotherSide(N);
      .my_name(Me);
      .send(H, askOne, findRobot(Me, _), Found, FT);
      !afterFind(H, Found, Ds).

+!showAnotherSide(0).
+!showAnotherSide(_) : find_turn(T) <- .print("I turn ", T, " degrees to show another side"); !turnInPlace(T).

+!turnInPlace(T) : settle_wait(W) <- turn(T); .wait(W).
-!turnInPlace(T) : settle_wait(W) <- .print("I could not turn ", T, " degrees"); .wait(W).

+!afterFind(H, findRobot(_, found), Ds) <- .progress(found_by, H); !tryMove(H, Ds, 1).
+!afterFind(H, findRobot(_, not_found), Ds) <- .print(H, " could not find me"); !findMe(H, Ds).
+!afterFind(H, Answer, Ds) <- .print(H, " could not find me (", Answer, ")"); !nextHelper(H, Ds).

+!nextHelper(H, Ds) <- -helper(H); !courtesy(H, thanks); !broadcastHelp(Ds).

// ---- the test motion, watched by the helper -----------------------------------------------------
+!tryMove(H, Ds, Trial) : answer_timeout(T)
   <- .my_name(Me);
      .send(H, askOne, trackMe(Me, _), Seen, T);
      !checkAnswer(H, Seen);
      !showSide(H, Ds, Trial, Seen).

// where the helper sees me from decides whether I turn first: my test motion must cross its view
+!showSide(H, Ds, Trial, trackMe(_, seen(B, _, Y))) : side_turn(B, Y, T) & T \== 0 & answer_timeout(TO)
   <- .print("I turn ", T, " degrees to show ", H, " my side");
      !turnInPlace(T);
      .my_name(Me);
      .send(H, askOne, trackMe(Me, _), Before, TO);
      !checkAnswer(H, Before);
      !afterTrack(H, Ds, Trial, Before).
+!showSide(H, Ds, Trial, Seen) <- !afterTrack(H, Ds, Trial, Seen).

+!afterTrack(H, Ds, _, trackMe(_, lost)) <- .print(H, " lost sight of me"); !findMe(H, Ds).
+!afterTrack(H, Ds, Trial, Before) : test_move(M) & encoders(L, R)
   <- .abolish(saw_over_current(_));
      .abolish(blocked);
      -+leg_start(L, R);
      .print("test motion: ", M, " m while ", H, " watches");
      !testMotion(M);
      !afterMotion(H, Ds, Trial, Before).

+!testMotion(M) <- move(M).
-!testMotion(M)[reason(bumper)] <- +blocked.
-!testMotion(M)[reason(R)] <- .print("the test motion failed too (", R, ")").

// A motion stopped by my bumper (a wall, a robot in front of me) shows what is in my way, not what my wheels
// can do: that motion is not diagnosed. I turn round (my other side faces the helper, as it should) and try
// again; blocked both ways, I give the helper up for another.
+!afterMotion(H, Ds, Trial, _) : blocked & max_trials(N) & Trial < N
   <- .print("something stopped my test motion: I turn round and try again");
      !turnInPlace(180);
      !tryMove(H, Ds, Trial + 1).
+!afterMotion(H, Ds, _, _) : blocked
   <- .print("something stopped my test motion both ways"); !nextHelper(H, Ds).
+!afterMotion(H, Ds, Trial, Before) : answer_timeout(T)
   <- .my_name(Me);
      .send(H, askOne, giveMeFeedback(Me, _), After, T);
      !checkAnswer(H, After);
      !ownObservations(Own);
      !withFeedback(H, Ds, Trial, Own, Before, After).

+!checkAnswer(H, timeout) <- .print(H, " did not answer in time"); .fail.
+!checkAnswer(H, false) <- .print(H, " could not answer"); .fail.
+!checkAnswer(H, _).

+!withFeedback(H, Ds, Trial, Own, trackMe(_, B), giveMeFeedback(_, A)) : model(Model)
   <- ?helper_obs(B, A, Seen);
      .concat(Own, Seen, Obs);
      .print(H, " saw me at ", B, " then ", A);
      .diagnose(Model, Obs, Ds2);
      .print("with ", H, "'s help, the diagnoser explains ", Obs, " by ", Ds2);
      !conclude(H, Ds2, Trial).

+!conclude(H, [D], _) <- !courtesy(H, thanks); -helper(H); !decide(D).
+!conclude(H, Ds, Trial) : max_trials(N) & Trial < N
   <- .print("still ambiguous: ", Ds, "; one more test motion"); !tryMove(H, Ds, Trial + 1).
+!conclude(H, Ds, _) <- !courtesy(H, thanks); -helper(H); !undiagnosed(Ds, ambiguous).

-!tryMove(H, Ds, _) <- .print("lost ", H, "'s help"); !nextHelper(H, Ds).
-!afterTrack(H, Ds, _, _) <- .print("lost ", H, "'s help"); !nextHelper(H, Ds).
-!withHelper(H, Ds) <- !nextHelper(H, Ds).

// ---- robustness: a helper that dies is replaced; nobody answering ends undiagnosed ---------------
-agent_alive(H) : helper(H) & diagnosing
   <- .print("my helper ", H, " is gone");
      .drop_desire(withHelper(H, _));
      .drop_desire(tryMove(H, _, _));
      -helper(H);
      ?candidates(Ds);
      !broadcastHelp(Ds).

// a helper that comes back (a frozen process thawed, a link restored) may be asked again
+agent_alive(H) : tried(H) & not helper(H) <- -tried(H).

+!undiagnosed(Ds, Why)
   <- .print("undiagnosed (", Why, "); candidates: ", Ds);
      -diagnosing;
      .progress(undiagnosed, Ds).
