// The `calibrate-lm` bench's problem solved by Ceres (Debian libceres-dev),
// for the speed comparison in the README's "Measured speed". Not part of
// cargo's build.
//
// The same least squares as aacmm's `lm` (core/src/residuals, method.md):
//   touch i of point k:  r_i = L_iᵀ (p(q_i; x) − c_k),  L_i L_iᵀ = A_i,
//     A_i = (σ_probe² I + σ_enc² J_q J_qᵀ)⁻¹ with J_q at the nominal arm;
//   length a–b:          r = w_L (|c̄_a − c̄_b| − L),
//     w_L = 1/sqrt(u_L² + uᵀ(C_a + C_b)u), C_k = (Σ_{i∈k} A_i)⁻¹, u the unit
//     vector between the points' first touches at the nominal arm, c̄_k =
//     C_k Σ A_i p_i the weighted centroid at x.
// The socket centres c_k of the touches are parameter blocks (Ceres
// eliminates them by its Schur complement, as aacmm does by the weighted
// centroids).
//
// Two programs (`MODE`):
//   autodiff  Ceres' Jets through the chain, one touch a residual block;
//             the lengths measure between the free centres, which they
//             pull (aacmm's are the weighted centroids): the optima differ
//             by that pull (printed);
//   analytic  the lengths measure between the weighted centroids at x, as
//             aacmm's do, so that both minimise the same function of x;
//             the closed-form columns aacmm's kernel uses
//             (∂p/∂θ_i = z_{i−1} × (p − o_{i−1}), ∂p/∂α_i = x_i × (p − o_i),
//             ∂p/∂a_i = x_i, ∂p/∂d_i = z_{i−1}, ∂p/∂B = R_n), the readings'
//             cos/sin computed once, the parameters' once per point, every
//             touch's position and Jacobian computed once per point in an
//             EvaluationCallback into buffers allocated once; the touch
//             blocks (SizedCostFunction<3, 27, 3>) and the length blocks
//             (SizedCostFunction<1, 27>) read them.
// LM, DENSE_SCHUR, 1 thread, aacmm's tolerances (1e-12).
//
// usage: ceres_lm DIR [REPEATS [autodiff|analytic]]   (DIR written by
// examples/ceres_export.rs; default 5 repeats, autodiff)
#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr int kJoints = 6;
constexpr int kParams = 4 * kJoints + 3;
// Free parameters of the bench's fixed set (method.md §8.1: θ1, d1, θ6, α6,
// Bx, By fixed): the analytic blocks' size, checked against the problem.
constexpr int kFree = kParams - 6;

// Probe position; params in DhParams::to_vec order: a[n], d[n], alpha[n],
// theta[n], Bx, By, Bz. A_j = Rz(θ+q)·Tz(d)·Tx(a)·Rx(α).
template <typename T, typename Q>
void Position(const T* x, const Q* q, T* out) {
  // Rows of the running transform t (3 × 4).
  T t[3][4] = {{T(1), T(0), T(0), T(0)}, {T(0), T(1), T(0), T(0)}, {T(0), T(0), T(1), T(0)}};
  for (int j = 0; j < kJoints; ++j) {
    const T a = x[j], d = x[kJoints + j], al = x[2 * kJoints + j], th = x[3 * kJoints + j];
    const T ang = th + q[j];
    const T ct = cos(ang), st = sin(ang), ca = cos(al), sa = sin(al);
    const T l[3][4] = {{ct, -ca * st, sa * st, a * ct}, {st, ca * ct, -sa * ct, a * st}, {T(0), sa, ca, d}};
    T r[3][4];
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 4; ++k) {
        r[i][k] = t[i][0] * l[0][k] + t[i][1] * l[1][k] + t[i][2] * l[2][k];
      }
      r[i][3] += t[i][3];
    }
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 4; ++k) t[i][k] = r[i][k];
  }
  const T* b = x + 4 * kJoints;
  for (int i = 0; i < 3; ++i) out[i] = t[i][0] * b[0] + t[i][1] * b[1] + t[i][2] * b[2] + t[i][3];
}

struct Touch {
  Touch(const double* q, const double* lt) {
    std::copy(q, q + kJoints, q_);
    std::copy(lt, lt + 9, lt_);
  }
  template <typename T>
  bool operator()(const T* x, const T* c, T* r) const {
    T p[3];
    Position(x, q_, p);
    const T e[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    for (int i = 0; i < 3; ++i) r[i] = lt_[3 * i] * e[0] + lt_[3 * i + 1] * e[1] + lt_[3 * i + 2] * e[2];
    return true;
  }
  double q_[kJoints];
  double lt_[9];  // Lᵀ, row-major
};

struct Length {
  Length(double l, double w) : l_(l), w_(w) {}
  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    const T d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    r[0] = w_ * (sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - l_);
    return true;
  }
  double l_, w_;
};

// Inverse of a symmetric 3 × 3 (row-major 9).
void Inv3(const double* m, double* o) {
  const double c00 = m[4] * m[8] - m[5] * m[7], c01 = m[5] * m[6] - m[3] * m[8], c02 = m[3] * m[7] - m[4] * m[6];
  const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  o[0] = c00 / det;
  o[1] = (m[2] * m[7] - m[1] * m[8]) / det;
  o[2] = (m[1] * m[5] - m[2] * m[4]) / det;
  o[3] = c01 / det;
  o[4] = (m[0] * m[8] - m[2] * m[6]) / det;
  o[5] = (m[2] * m[3] - m[0] * m[5]) / det;
  o[6] = c02 / det;
  o[7] = (m[1] * m[6] - m[0] * m[7]) / det;
  o[8] = (m[0] * m[4] - m[1] * m[3]) / det;
}

struct Data {
  int touches = 0, points = 0, lengths = 0;
  double enc = 0, probe = 0, len_default = 0;
  std::vector<double> nominal, aacmm;
  std::vector<int> fixed;
  double aacmm_cost = 0, aacmm_ms = 0;
  std::vector<int> point;
  std::vector<double> q;
  std::vector<int> la, lb;
  std::vector<double> ll, lu;
};

std::vector<double> Doubles(std::istringstream& s) {
  std::vector<double> v;
  double x;
  while (s >> x) v.push_back(x);
  return v;
}

bool Read(const std::string& dir, Data* d) {
  std::ifstream p(dir + "/problem.txt"), t(dir + "/touches.txt"), l(dir + "/lengths.txt"), a(dir + "/aacmm.txt");
  if (!p || !t || !l || !a) return false;
  std::string line;
  while (std::getline(p, line)) {
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (key == "joints") { int n; s >> n; if (n != kJoints) return false; }
    else if (key == "touches") s >> d->touches;
    else if (key == "points") s >> d->points;
    else if (key == "lengths") s >> d->lengths;
    else if (key == "encoder_rad") s >> d->enc;
    else if (key == "probe_mm") s >> d->probe;
    else if (key == "length_default_mm") s >> d->len_default;
    else if (key == "nominal") d->nominal = Doubles(s);
    else if (key == "fixed") { int f; while (s >> f) d->fixed.push_back(f); }
  }
  while (std::getline(a, line)) {
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (key == "params") d->aacmm = Doubles(s);
    else if (key == "cost") s >> d->aacmm_cost;
    else if (key == "ms") s >> d->aacmm_ms;
  }
  d->point.resize(d->touches);
  d->q.resize(d->touches * kJoints);
  for (int i = 0; i < d->touches; ++i) {
    t >> d->point[i];
    for (int j = 0; j < kJoints; ++j) t >> d->q[i * kJoints + j];
  }
  for (int i = 0; i < d->lengths; ++i) {
    int x, y;
    double L, u;
    l >> x >> y >> L >> u;
    d->la.push_back(x), d->lb.push_back(y), d->ll.push_back(L), d->lu.push_back(u);
  }
  return t && l && (int)d->nominal.size() == kParams && (int)d->fixed.size() == kParams &&
         (int)d->aacmm.size() == kParams;
}

struct Run {
  double ms_total, ms_solve, cost;
  int iterations;
  std::vector<double> x;
  double cost_at_aacmm;  // this problem's Σr² at aacmm's parameters, centres its centroids
};

// The weights at the nominal arm: per touch A_i and Lᵀ (L Lᵀ = A_i), per
// point C_k = (Σ A_i)⁻¹ and the weighted centroid (the centres' start), per
// length its w_L.
struct Weights {
  std::vector<double> lt, A, C, centres, length;

  explicit Weights(const Data& d) : lt(9 * d.touches), A(9 * d.touches), C(9 * d.points), centres(3 * d.points) {
    const double* x0 = d.nominal.data();
    std::vector<double> pos(3 * d.touches);
    using J = ceres::Jet<double, kJoints>;
    J xj[kParams];
    for (int k = 0; k < kParams; ++k) xj[k] = J(x0[k]);
    for (int i = 0; i < d.touches; ++i) {
      J qj[kJoints], p[3];
      for (int j = 0; j < kJoints; ++j) qj[j] = J(d.q[i * kJoints + j], j);
      Position(xj, qj, p);
      double cov[9];
      for (int r = 0; r < 3; ++r) {
        pos[3 * i + r] = p[r].a;
        for (int c = 0; c < 3; ++c) cov[3 * r + c] = d.enc * d.enc * p[r].v.dot(p[c].v) + (r == c ? d.probe * d.probe : 0.0);
      }
      double* a = &A[9 * i];
      Inv3(cov, a);
      // Cholesky A = L Lᵀ; store Lᵀ.
      const double l00 = std::sqrt(a[0]), l10 = a[3] / l00, l20 = a[6] / l00;
      const double l11 = std::sqrt(a[4] - l10 * l10), l21 = (a[7] - l20 * l10) / l11;
      const double l22 = std::sqrt(a[8] - l20 * l20 - l21 * l21);
      const double m[9] = {l00, l10, l20, 0, l11, l21, 0, 0, l22};
      std::copy(m, m + 9, &lt[9 * i]);
    }
    // Centres: weighted centroids at the nominal arm (aacmm's start too).
    std::vector<double> S(9 * d.points, 0.0), Sp(3 * d.points, 0.0);
    std::vector<int> first(d.points, -1);
    for (int i = 0; i < d.touches; ++i) {
      const int k = d.point[i];
      if (first[k] < 0) first[k] = i;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          S[9 * k + 3 * r + c] += A[9 * i + 3 * r + c];
          Sp[3 * k + r] += A[9 * i + 3 * r + c] * pos[3 * i + c];
        }
      }
    }
    for (int k = 0; k < d.points; ++k) {
      Inv3(&S[9 * k], &C[9 * k]);
      for (int r = 0; r < 3; ++r) {
        centres[3 * k + r] = 0;
        for (int c = 0; c < 3; ++c) centres[3 * k + r] += C[9 * k + 3 * r + c] * Sp[3 * k + c];
      }
    }
    for (int r = 0; r < d.lengths; ++r) {
      const int a = d.la[r], b = d.lb[r];
      const int ia = first[a], ib = first[b];
      double u[3], n = 0;
      for (int c = 0; c < 3; ++c) u[c] = pos[3 * ia + c] - pos[3 * ib + c], n += u[c] * u[c];
      n = std::sqrt(n);
      for (double& v : u) v /= n;
      auto along = [&](const double* cm) {
        double s = 0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) s += u[i] * cm[3 * i + j] * u[j];
        return s;
      };
      const double ul = d.lu[r] >= 0 ? d.lu[r] : d.len_default;
      length.push_back(1.0 / std::sqrt(ul * ul + along(&C[9 * a]) + along(&C[9 * b])));
    }
  }
};

// Solves `problem` (its parameter block `x`, the fixed parameters held) as
// aacmm's LM is set; the times from `t0` (the weights) and of Solve alone.
// `x`: every parameter, as one block whose fixed ones a manifold holds
// (null when the problem's block is the free parameters alone).
Run Finish(const Data& d, const Weights& W, ceres::Problem& problem, std::vector<double>* x,
           std::chrono::steady_clock::time_point t0) {
  std::vector<int> fixed;
  for (int k = 0; k < kParams; ++k)
    if (d.fixed[k]) fixed.push_back(k);
  if (x != nullptr) problem.SetManifold(x->data(), new ceres::SubsetManifold(kParams, fixed));
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = ceres::DENSE_SCHUR;
  if (const char* ls = std::getenv("CERES_LINEAR_SOLVER")) ceres::StringToLinearSolverType(ls, &o.linear_solver_type);
  o.num_threads = 1;
  o.max_num_iterations = 200;
  o.function_tolerance = 1e-12;
  o.parameter_tolerance = 1e-12;
  o.gradient_tolerance = 1e-12;
  o.logging_type = ceres::SILENT;
  ceres::Solver::Summary s;
  const auto t1 = std::chrono::steady_clock::now();
  ceres::Solve(o, &problem, &s);
  const auto t2 = std::chrono::steady_clock::now();
  Run run;
  run.ms_total = std::chrono::duration<double, std::milli>(t2 - t0).count();
  run.ms_solve = std::chrono::duration<double, std::milli>(t2 - t1).count();
  run.cost = 2.0 * s.final_cost;  // Ceres minimises ½Σr²; aacmm reports Σr².
  run.iterations = (int)s.iterations.size() - 1;
  if (x != nullptr) run.x = *x;
  // The same cost as aacmm's? At aacmm's parameters with the centres at the
  // weighted centroids (what aacmm eliminates them to), Σr² must be its cost.
  {
    const double* xa = d.aacmm.data();
    std::vector<double> P(3 * d.touches), Sa(3 * d.points, 0.0), ca(3 * d.points);
    for (int i = 0; i < d.touches; ++i) {
      Position(xa, &d.q[i * kJoints], &P[3 * i]);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) Sa[3 * d.point[i] + r] += W.A[9 * i + 3 * r + c] * P[3 * i + c];
    }
    for (int k = 0; k < d.points; ++k)
      for (int r = 0; r < 3; ++r) {
        ca[3 * k + r] = 0;
        for (int c = 0; c < 3; ++c) ca[3 * k + r] += W.C[9 * k + 3 * r + c] * Sa[3 * k + c];
      }
    double sum = 0;
    for (int i = 0; i < d.touches; ++i) {
      double r[3];
      Touch(&d.q[i * kJoints], &W.lt[9 * i])(xa, &ca[3 * d.point[i]], r);
      sum += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    }
    for (int r = 0; r < d.lengths; ++r) {
      double v;
      Length(d.ll[r], W.length[r])(&ca[3 * d.la[r]], &ca[3 * d.lb[r]], &v);
      sum += v * v;
    }
    run.cost_at_aacmm = sum;
  }
  if (s.termination_type == ceres::FAILURE) std::fprintf(stderr, "ceres: %s\n", s.message.c_str());
  if (std::getenv("CERES_REPORT") != nullptr) std::fprintf(stderr, "%s\n", s.FullReport().c_str());
  return run;
}

Run SolveAutodiff(const Data& d) {
  const auto t0 = std::chrono::steady_clock::now();
  Weights W(d);
  std::vector<double> x(d.nominal);
  std::vector<double> centres(W.centres);
  ceres::Problem::Options po;
  ceres::Problem problem(po);
  for (int i = 0; i < d.touches; ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Touch, 3, kParams, 3>(
                                 new Touch(&d.q[i * kJoints], &W.lt[9 * i])),
                             nullptr, x.data(), &centres[3 * d.point[i]]);
  }
  for (int r = 0; r < d.lengths; ++r) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<Length, 1, 3, 3>(new Length(d.ll[r], W.length[r])), nullptr,
        &centres[3 * d.la[r]], &centres[3 * d.lb[r]]);
  }
  return Finish(d, W, problem, &x, t0);
}

// ---- analytic: closed-form Jacobians, shared per point --------------------

// Everything a point's evaluation needs, allocated once: per touch the
// readings' cos/sin, its weight's Lᵀ, and at the current point its position
// and 3 × kParams Jacobian (row-major); per length socket its centroid and
// the centroid's Jacobian.
struct Shared : public ceres::EvaluationCallback {
  // The point: Ceres' block of the free parameters, put into every
  // parameter's vector `full` (the fixed ones at their nominal values).
  const double* xf = nullptr;
  std::vector<int> free;
  std::vector<double> full;
  const double* x = nullptr;  // = full.data()
  int touches = 0;
  std::vector<double> cq, sq;  // touches × kJoints
  std::vector<double> pos, jac;  // touches × 3, touches × 3 × kParams
  // Centroids of the sockets the lengths join: their touches' weights
  // M_i = C_k A_i, the centroid and its Jacobian.
  std::vector<int> point;
  std::vector<char> in_length;  // per point
  std::vector<double> m;  // touches × 9 (rows of touches of length sockets)
  std::vector<double> centroid, centroid_jac;  // points × 3, points × 3 × kFree
  std::vector<int> column;  // per parameter, its free column, or −1

  void PrepareForEvaluation(bool evaluate_jacobians, bool new_point) override {
    if (!new_point && (!evaluate_jacobians || jacobians_ready)) return;
    Evaluate(evaluate_jacobians);
    jacobians_ready = evaluate_jacobians;
  }
  bool jacobians_ready = false;

  void Evaluate(bool with_jacobians) {
    for (int a = 0; a < kFree; ++a) full[free[a]] = xf[a];
    x = full.data();
    double ct[kJoints], st[kJoints], ca[kJoints], sa[kJoints];
    for (int j = 0; j < kJoints; ++j) {
      ct[j] = std::cos(x[3 * kJoints + j]), st[j] = std::sin(x[3 * kJoints + j]);
      ca[j] = std::cos(x[2 * kJoints + j]), sa[j] = std::sin(x[2 * kJoints + j]);
    }
    std::fill(centroid.begin(), centroid.end(), 0.0);
    if (with_jacobians) std::fill(centroid_jac.begin(), centroid_jac.end(), 0.0);
    for (int i = 0; i < touches; ++i) {
      Chain(i, ct, st, ca, sa, with_jacobians);
      const int k = point[i];
      if (!in_length[k]) continue;
      const double* mi = &m[9 * i];
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) centroid[3 * k + r] += mi[3 * r + c] * pos[3 * i + c];
        if (!with_jacobians) continue;
        double* cj = &centroid_jac[(3 * k + r) * kFree];
        for (int c = 0; c < 3; ++c) {
          const double* ji = &jac[(3 * i + c) * kFree];
          for (int p = 0; p < kFree; ++p) cj[p] += mi[3 * r + c] * ji[p];
        }
      }
    }
  }

  // Touch i's position (and Jacobian columns) at the point.
  void Chain(int i, const double* ct, const double* st, const double* ca, const double* sa,
             bool with_jacobians) {
    // Frames 0..n: rotation columns x, z and origin o.
    double xs[kJoints + 1][3], zs[kJoints + 1][3], os[kJoints + 1][3];
    double t[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
    for (int r = 0; r < 3; ++r) xs[0][r] = t[r][0], zs[0][r] = t[r][2], os[0][r] = 0;
    for (int j = 0; j < kJoints; ++j) {
      const double cq_ = cq[i * kJoints + j], sq_ = sq[i * kJoints + j];
      const double c = ct[j] * cq_ - st[j] * sq_, s = st[j] * cq_ + ct[j] * sq_;
      const double a = x[j], d = x[kJoints + j];
      const double l[3][4] = {{c, -ca[j] * s, sa[j] * s, a * c}, {s, ca[j] * c, -sa[j] * c, a * s},
                              {0, sa[j], ca[j], d}};
      double r_[3][4];
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 4; ++k) r_[r][k] = t[r][0] * l[0][k] + t[r][1] * l[1][k] + t[r][2] * l[2][k];
        r_[r][3] += t[r][3];
      }
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 4; ++k) t[r][k] = r_[r][k];
        xs[j + 1][r] = t[r][0], zs[j + 1][r] = t[r][2], os[j + 1][r] = t[r][3];
      }
    }
    const double* b = x + 4 * kJoints;
    double* p = &pos[3 * i];
    for (int r = 0; r < 3; ++r) p[r] = t[r][0] * b[0] + t[r][1] * b[1] + t[r][2] * b[2] + t[r][3];
    if (!with_jacobians) return;
    double* J = &jac[3 * i * kFree];  // rows x, y, z; the free columns
    auto put = [&](int col, const double v[3]) {
      const int a = column[col];
      if (a < 0) return;
      for (int r = 0; r < 3; ++r) J[r * kFree + a] = v[r];
    };
    auto cross = [](const double u[3], const double v[3], double w[3]) {
      w[0] = u[1] * v[2] - u[2] * v[1], w[1] = u[2] * v[0] - u[0] * v[2], w[2] = u[0] * v[1] - u[1] * v[0];
    };
    for (int j = 0; j < kJoints; ++j) {
      double arm[3], w[3];
      put(j, xs[j + 1]);                 // ∂p/∂a_j = x_j
      put(kJoints + j, zs[j]);           // ∂p/∂d_j = z_{j−1}
      for (int r = 0; r < 3; ++r) arm[r] = p[r] - os[j + 1][r];
      cross(xs[j + 1], arm, w);
      put(2 * kJoints + j, w);           // ∂p/∂α_j = x_j × (p − o_j)
      for (int r = 0; r < 3; ++r) arm[r] = p[r] - os[j][r];
      cross(zs[j], arm, w);
      put(3 * kJoints + j, w);           // ∂p/∂θ_j = z_{j−1} × (p − o_{j−1})
    }
    for (int c = 0; c < 3; ++c) {
      const double col[3] = {t[0][c], t[1][c], t[2][c]};
      put(4 * kJoints + c, col);         // ∂p/∂B = R_n
    }
  }
};

class TouchCost : public ceres::SizedCostFunction<3, kFree, 3> {
 public:
  TouchCost(const Shared* shared, int i, const double* lt) : shared_(shared), i_(i) {
    std::copy(lt, lt + 9, lt_);
  }
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const double* p = &shared_->pos[3 * i_];
    const double* c = params[1];
    const double e[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    for (int r = 0; r < 3; ++r)
      residuals[r] = lt_[3 * r] * e[0] + lt_[3 * r + 1] * e[1] + lt_[3 * r + 2] * e[2];
    if (jacobians == nullptr) return true;
    if (jacobians[0] != nullptr) {
      const double* J = &shared_->jac[3 * i_ * kFree];
      for (int r = 0; r < 3; ++r) {
        double* out = jacobians[0] + r * kFree;
        for (int q = 0; q < kFree; ++q)
          out[q] = lt_[3 * r] * J[q] + lt_[3 * r + 1] * J[kFree + q] + lt_[3 * r + 2] * J[2 * kFree + q];
      }
    }
    if (jacobians[1] != nullptr)
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) jacobians[1][3 * r + k] = -lt_[3 * r + k];
    return true;
  }

 private:
  const Shared* shared_;
  int i_;
  double lt_[9];
};

class LengthCost : public ceres::SizedCostFunction<1, kFree> {
 public:
  LengthCost(const Shared* shared, int a, int b, double l, double w)
      : shared_(shared), a_(a), b_(b), l_(l), w_(w) {}
  bool Evaluate(double const* const*, double* residuals, double** jacobians) const override {
    const double* ca = &shared_->centroid[3 * a_];
    const double* cb = &shared_->centroid[3 * b_];
    const double d[3] = {ca[0] - cb[0], ca[1] - cb[1], ca[2] - cb[2]};
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    residuals[0] = w_ * (n - l_);
    if (jacobians == nullptr || jacobians[0] == nullptr) return true;
    for (int q = 0; q < kFree; ++q) {
      double v = 0;
      for (int r = 0; r < 3; ++r)
        v += d[r] / n * (shared_->centroid_jac[(3 * a_ + r) * kFree + q] -
                         shared_->centroid_jac[(3 * b_ + r) * kFree + q]);
      jacobians[0][q] = w_ * v;
    }
    return true;
  }

 private:
  const Shared* shared_;
  int a_, b_;
  double l_, w_;
};

Run SolveAnalytic(const Data& d) {
  const auto t0 = std::chrono::steady_clock::now();
  Weights W(d);
  std::vector<double> x(d.nominal);
  std::vector<double> centres(W.centres);
  Shared shared;
  shared.column.assign(kParams, -1);
  for (int k = 0; k < kParams; ++k)
    if (!d.fixed[k]) shared.column[k] = (int)shared.free.size(), shared.free.push_back(k);
  // The fixed parameters are no part of Ceres' problem: its block is the
  // free ones (no manifold to project every block's Jacobian through).
  std::vector<double> xf;
  for (int k : shared.free) xf.push_back(x[k]);
  shared.xf = xf.data();
  shared.full = d.nominal;
  shared.touches = d.touches;
  shared.cq.resize(d.touches * kJoints), shared.sq.resize(d.touches * kJoints);
  for (int k = 0; k < d.touches * kJoints; ++k) shared.cq[k] = std::cos(d.q[k]), shared.sq[k] = std::sin(d.q[k]);
  shared.pos.resize(3 * d.touches), shared.jac.resize(3 * d.touches * kFree);
  shared.point = d.point;
  shared.in_length.assign(d.points, 0);
  for (int r = 0; r < d.lengths; ++r) shared.in_length[d.la[r]] = shared.in_length[d.lb[r]] = 1;
  shared.m.assign(9 * d.touches, 0.0);
  for (int i = 0; i < d.touches; ++i) {
    const int k = d.point[i];
    if (!shared.in_length[k]) continue;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int e = 0; e < 3; ++e) shared.m[9 * i + 3 * r + c] += W.C[9 * k + 3 * r + e] * W.A[9 * i + 3 * e + c];
  }
  shared.centroid.resize(3 * d.points), shared.centroid_jac.resize(3 * d.points * kFree);
  ceres::Problem::Options po;
  po.evaluation_callback = &shared;
  ceres::Problem problem(po);
  for (int i = 0; i < d.touches; ++i)
    problem.AddResidualBlock(new TouchCost(&shared, i, &W.lt[9 * i]), nullptr, xf.data(),
                             &centres[3 * d.point[i]]);
  for (int r = 0; r < d.lengths; ++r)
    problem.AddResidualBlock(new LengthCost(&shared, d.la[r], d.lb[r], d.ll[r], W.length[r]), nullptr,
                             xf.data());
  Run run = Finish(d, W, problem, nullptr, t0);
  for (int a = 0; a < kFree; ++a) x[shared.free[a]] = xf[a];
  run.x = x;
  return run;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: ceres_lm DIR [REPEATS [autodiff|analytic]]\n");
    return 2;
  }
  Data d;
  if (!Read(argv[1], &d)) {
    std::fprintf(stderr, "ceres_lm: cannot read the files in %s\n", argv[1]);
    return 1;
  }
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  const std::string mode = argc > 3 ? argv[3] : "autodiff";
  if (mode != "autodiff" && mode != "analytic") {
    std::fprintf(stderr, "ceres_lm: mode %s: autodiff or analytic\n", mode.c_str());
    return 2;
  }
  const int nfree = kParams - (int)std::count(d.fixed.begin(), d.fixed.end(), 1);
  if (mode == "analytic" && nfree != kFree) {
    std::fprintf(stderr, "ceres_lm: analytic is compiled for %d free parameters, the problem has %d\n", kFree,
                 nfree);
    return 1;
  }
  auto solve = [&]() { return mode == "analytic" ? SolveAnalytic(d) : SolveAutodiff(d); };
  Run best = solve();
  for (int r = 1; r < repeats; ++r) {
    Run run = solve();
    if (run.ms_total < best.ms_total) best = run;
  }
  double dmm = 0, drad = 0;
  for (int k = 0; k < kParams; ++k) {
    const double diff = std::fabs(best.x[k] - d.aacmm[k]);
    const bool angle = k >= 2 * kJoints && k < 4 * kJoints;
    (angle ? drad : dmm) = std::max(angle ? drad : dmm, diff);
  }
  // mode touches ceres_total_ms ceres_solve_ms aacmm_ms ceres_cost aacmm_cost
  // iterations max_dmm max_drad, the relative difference of the two
  // problems' cost at aacmm's solution, and of the two minima's costs
  std::printf("%s %d %.4f %.4f %.4f %.9e %.9e %d %.3e %.3e %.1e %.1e\n", mode.c_str(), d.touches,
              best.ms_total, best.ms_solve, d.aacmm_ms, best.cost, d.aacmm_cost, best.iterations, dmm, drad,
              std::fabs(best.cost_at_aacmm - d.aacmm_cost) / d.aacmm_cost,
              std::fabs(best.cost - d.aacmm_cost) / d.aacmm_cost);
  return 0;
}
