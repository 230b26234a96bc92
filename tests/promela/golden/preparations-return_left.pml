/* overtake-mc: preparations model, goal return_left; rendered from spec/, do not edit */
#define AV_CELL 10
#define DANGER 0
#define MAX_LC 1
#define MAXL 51
#define MAXR 51
#define LEFT 0
#define RIGHT 1

short left[MAXL];   /* left-lane vehicles, ascending */
short right[MAXR];  /* oncoming vehicles, ascending */
byte nl; byte nr; byte nt; byte ft; byte horizon;  /* the scenario: constant after start */
bit lane; byte lc; byte steps; bool crashed; bool reached;
byte firsts;  /* the first actions allowed (bit per action) */
bit least;  /* the commitment semantics' prediction: one action at least, the start unchecked (the sound model checked it) */
byte i;  /* scratch index, reset to 0 at the end of every atomic step, so it is constant */

inline collide() {
  if
  :: lane == LEFT ->
     i = 0; do :: i < nl -> crashed = crashed || left[i] == AV_CELL; i++ :: else -> break od
  :: else ->
     i = 0; do :: i < nr -> crashed = crashed || (right[i] >= AV_CELL - DANGER && right[i] <= AV_CELL + DANGER); i++
               :: else -> break od
  fi
}
inline shift_left(d) { i = 0; do :: i < nl -> left[i] = left[i] + d; i++ :: else -> break od }
inline tick() { i = 0; do :: i < nr -> right[i] = right[i] - 1; i++ :: else -> break od; collide() }
inline print_state() {
  printf("%d %d %d |", lane, lc, steps);
  i = 0; do :: i < nl -> printf(" %d", left[i]); i++ :: else -> break od; printf(" |");
  i = 0; do :: i < nr -> printf(" %d", right[i]); i++ :: else -> break od; printf("\n")
}
inline goal_check() {
  reached = 1;
  reached = reached && lane == LEFT;
  i = 0; do :: i < nr -> reached = reached && right[i] <= AV_CELL; i++ :: else -> break od;
}
active proctype av() {
  c_code {
    char *text = getenv("OVERTAKE_SCENARIO"); char *end; long v[2 * MAXL + 10]; int n = 0, j, at;
    if (!text) { fprintf(stderr, "overtake: OVERTAKE_SCENARIO is not set\n"); exit(2); }
    while (n < 2 * MAXL + 10) { v[n] = strtol(text, &end, 10); if (end == text) break; n++; text = end; }
    at = 0; now.lane = v[at++]; now.nl = v[at++];
    for (j = 0; j < now.nl; j++) now.left[j] = v[at++];
    now.nr = v[at++];
    for (j = 0; j < now.nr; j++) now.right[j] = v[at++];
    now.nt = v[at++]; now.ft = v[at++]; now.horizon = v[at++];
    if (at + 2 != n || v[at] < 0 || v[at] > 31 || v[at + 1] < 0 || v[at + 1] > 1) {
      fprintf(stderr, "overtake: malformed OVERTAKE_SCENARIO (the first actions allowed)\n"); exit(2); }
    now.firsts = v[at++]; now.least = v[at++];
    if (at != n || now.nl > MAXL || now.nr > MAXR || now.horizon > 200) {
      fprintf(stderr, "overtake: malformed OVERTAKE_SCENARIO\n"); exit(2); }
  };
  d_step { if :: !least -> collide() :: else -> skip fi;
           if :: !crashed -> printf("INIT "); print_state(); goal_check(); reached = reached && !least :: else -> skip fi;
           assert(!reached); i = 0 }
  do
  :: d_step { !crashed && steps < horizon && (steps > 0 || ((firsts >> 0) & 1)) && lane == RIGHT && lc < MAX_LC ->
       lane = LEFT; lc++; steps++; collide(); tick(); tick();
       if :: !crashed -> printf("STEP left_lane_change "); print_state(); goal_check(); assert(!reached) :: else -> skip fi; i = 0 }
  :: d_step { !crashed && steps < horizon && (steps > 0 || ((firsts >> 1) & 1)) ->
       shift_left(-1); steps++; collide(); tick(); tick(); tick();
       if :: !crashed -> printf("STEP accelerate "); print_state(); goal_check(); assert(!reached) :: else -> skip fi; i = 0 }
  :: d_step { !crashed && steps < horizon && (steps > 0 || ((firsts >> 2) & 1)) && lane == LEFT && lc < MAX_LC ->
       lane = RIGHT; lc++; steps++; collide(); tick(); tick();
       if :: !crashed -> printf("STEP right_lane_change "); print_state(); goal_check(); assert(!reached) :: else -> skip fi; i = 0 }
  :: d_step { !crashed && steps < horizon && (steps > 0 || ((firsts >> 3) & 1)) ->
       steps++; collide(); tick(); tick();
       if :: !crashed -> printf("STEP drive "); print_state(); goal_check(); assert(!reached) :: else -> skip fi; i = 0 }
  :: d_step { !crashed && steps < horizon && (steps > 0 || ((firsts >> 4) & 1)) ->
       shift_left(1); steps++; collide(); tick(); tick(); tick();
       if :: !crashed -> printf("STEP brake "); print_state(); goal_check(); assert(!reached) :: else -> skip fi; i = 0 }
  od
}
