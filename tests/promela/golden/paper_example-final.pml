/* overtake-mc: final model, goal overtake; rendered from spec/, do not edit */
#define AV_CELL 10
#define DANGER 1
#define MAX_LC 2
#define MAXL 2
#define MAXR 1
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
  i = ft; do :: i < ft + nt -> reached = reached && left[i] < AV_CELL; i++ :: else -> break od;
}
active proctype av() {
  d_step { lane = 0; nl = 2; nr = 1; nt = 2; ft = 0; horizon = 30; firsts = 31; least = 0; left[0] = 12; left[1] = 14; right[0] = 40 }
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
