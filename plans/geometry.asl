// Angles and absolute values for the cooperative fault plans (included by faulty.asl and helper.asl).
norm(A, N) :- A > 180 & N = A - 360.
norm(A, N) :- A <= -180 & N = A + 360.
norm(A, A) :- A > -180 & A <= 180.
abs(X, Y) :- X < 0 & Y = -X.
abs(X, X) :- X >= 0.

// The direction (degrees, counter-clockwise from the x axis) of the vector (DX, DY): atan2 in rules.
direction(DX, DY, A) :- DX > 0 & A = math.atan(DY / DX) * 180 / math.pi.
direction(DX, DY, A) :- DX < 0 & DY >= 0 & A = math.atan(DY / DX) * 180 / math.pi + 180.
direction(DX, DY, A) :- DX < 0 & DY < 0 & A = math.atan(DY / DX) * 180 / math.pi - 180.
direction(DX, DY, 90) :- DX == 0 & DY >= 0.
direction(DX, DY, -90) :- DX == 0 & DY < 0.

// Where I am in the team's shared frame (metres, degrees): my start pose in it, start_pose(X, Y, YawDeg),
// given at launch as a localisation's initial pose is, composed with my odometry (origin: where I started).
team_pose(X, Y, Yaw) :- start_pose(SX, SY, SYaw) & odom(OX, OY, OYaw) & R = SYaw * math.pi / 180 &
    X = SX + OX * math.cos(R) - OY * math.sin(R) & Y = SY + OX * math.sin(R) + OY * math.cos(R) &
    norm(SYaw + OYaw, Yaw).
