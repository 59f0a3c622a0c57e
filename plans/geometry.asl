// Angles and absolute values for the cooperative fault plans (included by faulty.asl and helper.asl).
norm(A, N) :- A > 180 & N = A - 360.
norm(A, N) :- A <= -180 & N = A + 360.
norm(A, A) :- A > -180 & A <= 180.
abs(X, Y) :- X < 0 & Y = -X.
abs(X, X) :- X >= 0.
