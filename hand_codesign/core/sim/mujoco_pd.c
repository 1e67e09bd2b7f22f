/*
 * Eq. (1), the feed-forward PD law, stepped in C on a MuJoCo scene (core.sim.mujoco_native).
 *
 * The law and its arithmetic are those of core.sim.mujoco_sim.mujoco_torques, operation for
 * operation, so that both give the same bits (compiled without floating-point contraction):
 *     a = -(kd edot + kp (e + h edot)) * scale,   scale = 2 / (1 + h kd)   (twice a)
 *     tau = [ID(theta, thetad + thetad_d, 2a) - ID(theta, thetad - thetad_d, -2a)] / 4
 *         = M(theta) a + C(theta, thetad) thetad_d
 * with ID MuJoCo's recursive Newton-Euler inverse dynamics (mj_rne) on a scratch mjData;
 * N(theta) is the model's gravcomp (core.policies and core.sim.mujoco_sim say why).
 *
 * The position-dependent quantities ID needs (cdof, cinert) are the ones mj_step1 has just
 * computed on the scene's own mjData from the same joint angles: copied, not recomputed.
 */

#include <mujoco/mujoco.h>

/* The constants of one PD policy over one rollout, laid out by core.sim.mujoco_native. */
typedef struct {
  int joints;                       /* the hand's joints: the first nq, nv entries */
  int num_steps;                    /* rows of targets and target_velocities */
  const mjtNum* gains;              /* joints x 4: kp, kd, h, scale (PDPolicy.step_gains) */
  const mjtNum* targets;            /* num_steps x joints: theta_d (rad) */
  const mjtNum* target_velocities;  /* num_steps x joints: thetad_d (rad/s) */
} hc_pd_law;

/* Write ID(theta, velocities, accelerations) of every dof into out (nv). */
static void inverse_dynamics(const mjModel* m, mjData* s, int joints,
                             const mjtNum* velocities, const mjtNum* accelerations,
                             mjtNum* out) {
  for (int j = 0; j < joints; j++) {
    s->qvel[j] = velocities[j];
    s->qacc[j] = accelerations[j];
  }
  mj_comVel(m, s);
  mj_rne(m, s, 1, out);
}

/*
 * Narrow `hand`, a copy of the scene's model, to the bodies and dofs the law's ID needs.
 *
 * Those are the bodies up to the last that one of the hand's joints moves, when no later body
 * hangs from them (the object is a free body under the world, after the hand) and their dofs
 * are the hand's: ID of a hand's dof sums forces of its subtree only, and MuJoCo's passes run
 * over bodies in order, so the narrowed model gives the same operations on the same numbers,
 * the same bits, without the object's body and its six dofs (on Task 5's hand a third of the
 * law's work, 1 to 3 % of an evaluation). Otherwise `hand` stays the whole model.
 */
static void narrow_to_hand(mjModel* hand, int joints) {
  int bodies = 1, dofs = 0;
  for (int j = 0; j < joints; j++) {
    if (hand->dof_bodyid[j] >= bodies) {
      bodies = hand->dof_bodyid[j] + 1;
    }
  }
  for (int b = 1; b < bodies; b++) {
    dofs += hand->body_dofnum[b];
  }
  for (int b = bodies; b < hand->nbody; b++) {
    if (hand->body_rootid[b] < bodies) {
      return;
    }
  }
  if (dofs == joints) {
    hand->nbody = bodies;
    hand->nv = joints;
  }
}

/*
 * Write the law's torques of `step` into d's qfrc_applied (the first `joints` dofs); `m` is
 * the scene's model, narrowed to the hand (narrow_to_hand).
 */
static void pd_torques(const mjModel* m, mjData* d, mjData* s, const hc_pd_law* law,
                       int step) {
  int joints = law->joints, nv = m->nv;
  const mjtNum* targets = law->targets + (size_t)step * joints;
  const mjtNum* target_velocities = law->target_velocities + (size_t)step * joints;
  mjtNum plus_velocity[joints], minus_velocity[joints];
  mjtNum plus_acceleration[joints], minus_acceleration[joints];
  mjtNum plus[nv], minus[nv];
  for (int j = 0; j < joints; j++) {
    const mjtNum* gain = law->gains + 4 * j;
    mjtNum q = d->qpos[j], v = d->qvel[j], qd = targets[j], vd = target_velocities[j];
    mjtNum edot = v - vd;
    mjtNum twice_a = -(gain[1] * edot + gain[0] * (q - qd + gain[2] * edot)) * gain[3];
    plus_velocity[j] = v + vd;
    minus_velocity[j] = v - vd;
    plus_acceleration[j] = twice_a;
    minus_acceleration[j] = -twice_a;
  }
  /* d's kinematics are of the current angles (mj_step1): the scratch takes what ID reads */
  mju_copy(s->cdof, d->cdof, 6 * nv);
  mju_copy(s->cinert, d->cinert, 10 * m->nbody);
  inverse_dynamics(m, s, joints, plus_velocity, plus_acceleration, plus);
  inverse_dynamics(m, s, joints, minus_velocity, minus_acceleration, minus);
  for (int j = 0; j < joints; j++) {
    d->qfrc_applied[j] = (plus[j] - minus[j]) * 0.25;
  }
}

/*
 * Step d from step `from` to step `to` (to <= law->num_steps) under the law; return the
 * steps taken (to - from), or -1 if the steps lie outside the law's rows.
 *
 * Each step is mj_step1, the law, mj_step2: with the Euler integrator that is mj_step bit
 * for bit, with the torques set from the state at the step's start, as the Python loop does.
 *
 * MuJoCo's profiler is off meanwhile: the Python bindings install a wall clock as mjcb_time
 * when they make an mjData, and the engine reads it about 30 times a step, a tenth of an
 * evaluation of these small scenes. It only fills d->timer, which nothing here reads; the
 * physics is the same bit for bit. The clock is put back for the rest of the process (two
 * threads stepping at once could at worst leave the profiler off).
 */
int hc_pd_advance(const mjModel* m, mjData* d, mjData* s, const hc_pd_law* law,
                  int from, int to) {
  if (from < 0 || to > law->num_steps || from > to) {
    return -1;
  }
  mjModel hand = *m;
  narrow_to_hand(&hand, law->joints);
  mjfTime clock = mjcb_time;
  mjcb_time = NULL;
  for (int step = from; step < to; step++) {
    mj_step1(m, d);
    pd_torques(&hand, d, s, law, step);
    mj_step2(m, d);
  }
  mjcb_time = clock;
  return to - from;
}
