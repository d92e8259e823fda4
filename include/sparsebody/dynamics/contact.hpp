// Ground / static-box contact: a stiff spring-damper per contact point made linearly implicit
// inside ABA, with Coulomb friction resolved by a small active-set loop.
//
// Why this method: at h = 1/120 s an explicit penalty spring on a light foot corner must stay below
// ~1e4 N/m, which lets a 63 kg avatar sink centimetres. Evaluating the contact force at the end of
// the step, F = k d+ - b v+ with v+ = v + h a and d+ = d - h v+ (n-components), makes it linear in
// the body's acceleration: F = F0 - h C a_p with C = (b + h k) n n^T (+ c_t (I - n n^T) while
// sticking). A force linear in the body's own acceleration is exactly an added articulated inertia,
// so it enters ABA as I^A_i += h P^T C P, p^A_i -= P^T F0' (P maps a spatial acceleration to the
// point's linear acceleration). The step stays O(n), needs no Delassus matrix, and is stable for
// any k, b. Because d+ uses the next velocity the contact is also predictive: points within
// `margin` above the surface are candidates and push only if they would penetrate next step,
// which removes the rest jitter of contacts that switch on and off.
// Unilateral and Coulomb conditions are enforced by re-solving (ABA passes 2-3 only, the
// kinematics are reused): a contact whose normal force comes out negative is dropped; a sticking
// contact whose tangential force exceeds mu Fn switches to sliding, where the tangential force is
// the explicit mu Fn along the direction of the sticking force. At most `max_passes` solves.
#pragma once
#include <array>

#include "sparsebody/dynamics/aba.hpp"

namespace sparsebody::dynamics {

template <class S>
struct ContactParams {
  S stiffness = S(2e5);            // k [N/m] per point: rest penetration m g / (n k) (63 kg on 8: 0.4 mm)
  S damping = S(2e3);              // b [N s/m] normal
  S tangential_damping = S(1e4);   // c_t [N s/m] while sticking: residual creep F_t / c_t
  S friction = S(1.0);             // mu (Coulomb), floor and boxes
  S margin = S(0.01);              // [m] predictive distance for candidates
  S slip_eps = S(1e-3);            // [m/s] slip speed floor in the sliding damper mu Fn / |v_t|
  int max_passes = 6;              // ABA solves per step (1 + active-set / friction updates); < 1 acts as 1
};

template <class S>
struct StaticBox {
  Vec3<S> center = Vec3<S>::Zero();
  Mat3<S> R = Mat3<S>::Identity();  // box axes in world
  Vec3<S> half = Vec3<S>::Constant(S(0.5));
};

template <class S, int MaxBoxes = 8>
struct Environment {
  bool ground = true;
  Vec3<S> ground_normal = Vec3<S>::UnitY();  // plane n.x = ground_offset
  S ground_offset = S(0);
  std::array<StaticBox<S>, MaxBoxes> boxes{};
  int num_boxes = 0;
  bool add_box(const StaticBox<S>& b) {
    if (num_boxes >= MaxBoxes) return false;
    boxes[num_boxes++] = b;
    return true;
  }
};

template <class S>
struct Contact {
  int body = 0;
  Vec3<S> p = Vec3<S>::Zero();      // contact point on the body surface, body coordinates
  Vec3<S> n = Vec3<S>::UnitY();     // world normal (pointing out of the obstacle)
  S depth = S(0);                   // penetration (> 0) or -distance (< 0, predictive)
  bool active = true;
  bool sliding = false;
  S slide_damping = S(0);                    // tangential damper while sliding [N s/m]
  int flips = 0;                             // active-set changes of this contact in this step
  Vec3<S> force = Vec3<S>::Zero();           // world force on the body, after the solve
  int point = -1, obstacle = -1;             // which model point against which obstacle (0: ground, 1 + box)
};

// Signed distance from a point to a static box and the outward normal.
template <class S>
inline S box_distance(const StaticBox<S>& b, const Vec3<S>& x, Vec3<S>& normal) {
  const Vec3<S> l = b.R.transpose() * (x - b.center);
  const Vec3<S> dd = l.cwiseAbs() - b.half;
  if (dd.maxCoeff() < S(0)) {
    int k;
    const S dist = dd.maxCoeff(&k);
    normal = b.R.col(k) * (l(k) < S(0) ? S(-1) : S(1));
    return dist;
  }
  const Vec3<S> q = l.cwiseMax(-b.half).cwiseMin(b.half);
  const Vec3<S> diff = l - q;
  const S dist = diff.norm();
  normal = b.R * (diff / dist);
  return dist;
}

// Candidate contacts from the model's contact points (needs world poses in d).
// Returns the number written (at most MaxContacts; `overflow` counts the ones dropped).
// prev/nprev (optional): the previous step's contacts after their solve. A contact between the same
// point and obstacle that was sliding starts sliding with the damper it converged to (warm start):
// a foot that keeps slipping under steady torques then needs one solve instead of the 3 passes that
// discover the slip and refine c_s.
template <class S, int MB, int MD, int MaxBoxes, std::size_t MaxContacts>
inline int detect_contacts(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d, const Environment<S, MaxBoxes>& env,
                          const ContactParams<S>& par, std::array<Contact<S>, MaxContacts>& out, int& overflow,
                          const Contact<S>* prev = nullptr, int nprev = 0) {
  int nc = 0;
  overflow = 0;
  int cursor = 0;  // contacts come out ordered by (point, obstacle), in both steps
  auto push = [&](int body, const Vec3<S>& centre_w, S radius, const Vec3<S>& n, S dist, int point, int obstacle) {
    if (nc >= int(MaxContacts)) { ++overflow; return; }
    Contact<S>& c = out[nc++];
    c.point = point;
    c.obstacle = obstacle;
    c.body = body;
    c.n = n;
    c.depth = -dist;
    c.p = d.R[body].transpose() * (centre_w - radius * n - d.p[body]);
    c.active = true;
    c.sliding = false;
    c.slide_damping = S(0);
    c.flips = 0;
    // A point already slipping starts in sliding mode, with Fn guessed from the spring-damper at
    // the current state (refined by the passes); a sticking first guess would need a huge
    // tangential force to stop it and distort the normal forces of that pass.
    const Vec3<S> vpw = point_velocity(d, body, c.p);
    const S vn = vpw.dot(n);
    const S vt = (vpw - vn * n).norm();
    if (vt > S(10) * par.slip_eps) {
      const S fn0 = std::max(S(0), par.stiffness * c.depth - par.damping * vn);
      c.sliding = true;
      c.slide_damping = std::min(par.tangential_damping, par.friction * fn0 / vt);
    }
    while (cursor < nprev && (prev[cursor].point < point || (prev[cursor].point == point && prev[cursor].obstacle < obstacle)))
      ++cursor;
    if (cursor < nprev && prev[cursor].point == point && prev[cursor].obstacle == obstacle && prev[cursor].active &&
        prev[cursor].sliding && vt > par.slip_eps) {
      c.sliding = true;
      c.slide_damping = prev[cursor].slide_damping;
    }
    c.force.setZero();
  };
  for (int k = 0; k < m.num_points; ++k) {
    const ContactPoint<S>& cp = m.points[k];
    const Vec3<S> x = d.p[cp.body] + d.R[cp.body] * cp.pos;
    if (env.ground) {
      const S dist = env.ground_normal.dot(x) - env.ground_offset - cp.radius;
      if (dist < par.margin) push(cp.body, x, cp.radius, env.ground_normal, dist, k, 0);
    }
    for (int b = 0; b < env.num_boxes; ++b) {
      Vec3<S> n;
      const S dist = box_distance(env.boxes[b], x, n) - cp.radius;
      if (dist < par.margin) push(cp.body, x, cp.radius, n, dist, k, 1 + b);
    }
  }
  return nc;
}

// Contact c's linearisation in body coordinates: world force F = F0 - h C a_p with
// a_p = P a + beta (a: the body's ABA acceleration including the fictitious -g, beta the known
// velocity-product and gravity terms). Writes C_b (body) and F0' = F0 - h C beta (body).
template <class S, int MB, int MD>
inline void contact_linearization(const Data<S, MB, MD>& d, const Contact<S>& c, const ContactParams<S>& par,
                                 const Vec3<S>& gravity, S h, Mat3<S>& Cb, Vec3<S>& F0b, Vec3<S>* vp_out = nullptr,
                                 Vec3<S>* beta_out = nullptr) {
  const Mat3<S>& R = d.R[c.body];
  const Vec6<S>& v = d.v[c.body];
  const Vec3<S> w = v.template head<3>();
  const Vec3<S> vp = Vec3<S>(v.template tail<3>()) + w.cross(c.p);  // point velocity, body coords
  const Vec3<S> nb = R.transpose() * c.n;
  const Mat3<S> nn = nb * nb.transpose();
  const S cn = par.damping + h * par.stiffness;  // (b + h k): the spring acts on d+ = d - h v+
  Cb = cn * nn;
  Cb += (c.sliding ? c.slide_damping : par.tangential_damping) * (Mat3<S>::Identity() - nn);
  // ABA's a_i carries -g as a base acceleration: a_true = a + (0, R^T g) (pure linear part).
  const Vec3<S> beta = w.cross(vp) + R.transpose() * gravity;
  F0b = par.stiffness * c.depth * nb - Cb * vp - h * (Cb * beta);
  if (vp_out) *vp_out = vp;
  if (beta_out) *beta_out = beta;
}

// Adds every active contact to d.Kext / d.fext (h P^T C P and P^T F0').
template <class S, int MB, int MD, std::size_t MaxContacts>
inline void assemble_contacts(const Model<S, MB, MD>& m, Data<S, MB, MD>& d, const std::array<Contact<S>, MaxContacts>& cs,
                             int nc, const ContactParams<S>& par, S h) {
  for (int i = 0; i < m.nb; ++i) { d.fext[i].setZero(); d.Kext[i].setZero(); }
  d.has_ext = true;
  for (int k = 0; k < nc; ++k) {
    const Contact<S>& c = cs[k];
    if (!c.active) continue;
    Mat3<S> Cb;
    Vec3<S> F0b;
    contact_linearization(d, c, par, m.gravity, h, Cb, F0b);
    const Mat3<S> px = skew(c.p);
    // P = [-p^, I]; P^T C P = [-p^ C p^... ] written blockwise: [[-p^Cp^, p^C], [-Cp^, C]] * h
    const Mat3<S> pxC = px * Cb;
    Mat6<S>& K = d.Kext[c.body];
    K.template topLeftCorner<3, 3>() -= h * (pxC * px);
    K.template topRightCorner<3, 3>() += h * pxC;
    K.template bottomLeftCorner<3, 3>() -= h * (Cb * px);
    K.template bottomRightCorner<3, 3>() += h * Cb;
    Vec6<S>& f = d.fext[c.body];
    f.template head<3>() += c.p.cross(F0b);
    f.template tail<3>() += F0b;
  }
}

// After a solve: evaluates each contact force, updates the active set. Returns true if it changed.
template <class S, int MB, int MD, std::size_t MaxContacts>
inline bool update_contact_set(const Model<S, MB, MD>& m, const Data<S, MB, MD>& d, std::array<Contact<S>, MaxContacts>& cs,
                             int nc, const ContactParams<S>& par, S h) {
  bool changed = false;
  for (int k = 0; k < nc; ++k) {
    Contact<S>& c = cs[k];
    Mat3<S> Cb;
    Vec3<S> F0b, vp;
    contact_linearization(d, c, par, m.gravity, h, Cb, F0b, &vp);
    const Vec6<S>& a = d.a[c.body];
    const Vec3<S> Pa = Vec3<S>(a.template tail<3>()) - c.p.cross(Vec3<S>(a.template head<3>()));  // P a
    const Vec3<S> F = d.R[c.body] * (F0b - h * (Cb * Pa));
    const S fn = F.dot(c.n);
    if (!c.active) {
      // Dropped earlier in this step: bring it back (sticking) if, with the current solution, it
      // would now push, i.e. the point would penetrate. At most one drop and one return per step.
      c.force.setZero();
      if (fn > S(0) && c.flips == 1) {
        c.active = true;
        c.sliding = false;
        ++c.flips;
        changed = true;
      }
      continue;
    }
    c.force = F;
    // Would pull: not in contact. A contact that was dropped and came back keeps its slight pull
    // for the rest of the step instead of cycling (the classic active-set ping-pong).
    if (fn <= S(0) && c.flips == 0) {
      c.active = false;
      c.force.setZero();
      ++c.flips;
      changed = true;
      continue;
    }
    const Vec3<S> ft = F - fn * c.n;
    const S ftn = ft.norm();
    // Sliding friction is a tangential damper sized from the slip speed at the start of the step,
    // c_s = mu Fn / max(|v_t|, slip_eps), so that c_s |v_t+| ~ mu Fn while the slip speed
    // changes little within a step (a one-step lag when it starts or stops sliding). Being a damper it
    // is implicit and dissipative whatever the estimate, so a stale Fn or slip speed can never
    // inject energy or reverse the slip; Fn is refreshed on every pass.
    const Vec3<S> vw = d.R[c.body] * vp;
    const S vt = (vw - vw.dot(c.n) * c.n).norm();
    const S cs = std::min(par.tangential_damping, par.friction * std::max(fn, S(0)) / std::max(vt, par.slip_eps));
    if (!c.sliding) {
      if (ftn > par.friction * fn) {
        c.sliding = true;
        c.slide_damping = cs;
        changed = true;
      }
    } else if (std::abs(cs - c.slide_damping) > S(0.05) * c.slide_damping) {
      c.slide_damping = cs;
      changed = true;
    }
  }
  return changed;
}

}  // namespace sparsebody::dynamics
