// A robot of a team that stays up and takes one task after another (team_robot.asl, then new tasks), as a
// real team does between repairs: issue 22's soak runs six of them for an hour, a fault injected into one
// robot per task.
//
// task(N, X, Y, YawDeg): told by whoever runs the team (a fleet manager), once the robot stands still and
// its odometry was reset: the task's number and where the robot stands in the team's shared frame (its
// localisation's pose, which team_pose composes with odometry). The robot was repaired since its last
// diagnosis, so it forgets that diagnosis's state (it suspects itself no more and may help again), then
// goes to its destination again; its steps are reported with .progress as in the first task.
// A task that ran past its budget may have left a conversation going (a diagnosis waiting for a helper, a
// search for a robot that has a new task too): the new task ends it, on both sides, so that the robot is
// free to help and nobody waits for an answer about the old task.
{ include("team_robot.asl") }

+task(N, X, Y, Yaw)
   <- .drop_all_intentions;
      .abolish(task(_, _, _, _));
      .abolish(self_suspect); .abolish(diagnosing); .abolish(on_mission);
      .abolish(tried(_)); .abolish(helper(_)); .abolish(canHelp); .abolish(candidates(_));
      .abolish(finds(_, _)); .abolish(saw_over_current(_)); .abolish(leg_start(_, _)); .abolish(blocked);
      .abolish(helping(_)); .abolish(help_at(_, _)); .abolish(stepped(_)); .abolish(home_yaw(_));
      .abolish(noThanks); .abolish(thanks);
      .abolish(start_pose(_, _, _));
      +start_pose(X, Y, Yaw);
      .progress(task, N);
      !goToDestination.
