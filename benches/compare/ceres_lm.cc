// The `lm` bench's problem solved by Ceres (Debian libceres-dev), for the
// speed comparison in README's "Scale" section. Not part of cargo's build.
//
// Same least squares as aacmm's `lm` (core/src/residuals.rs, method.md):
//   touch i of point k:  r_i = L_iᵀ (p(q_i; x) − c_k),  L_i L_iᵀ = A_i,
//     A_i = (σ_probe² I + σ_enc² J_q J_qᵀ)⁻¹ with J_q at the nominal arm;
//   length a–b:          r = w_L (|c_a − c_b| − L),
//     w_L = 1/sqrt(u_L² + uᵀ(C_a + C_b)u), C_k = (Σ_{i∈k} A_i)⁻¹, u the unit
//     vector between the points' first touches at the nominal arm.
// The socket centres c_k are parameter blocks (aacmm eliminates them as
// weighted centroids; the lengths there use the centroids, here they pull
// the centres, so the optima differ by the lengths' pull: printed).
// LM, autodiff, DENSE_SCHUR, 1 thread, aacmm's tolerances (1e-12).
//
// usage: ceres_lm DIR [REPEATS]   (DIR written by examples/ceres_export.rs)
#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr int kJoints = 6;
constexpr int kParams = 4 * kJoints + 3;

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

Run Solve(const Data& d) {
  const auto t0 = std::chrono::steady_clock::now();
  const double* x0 = d.nominal.data();
  // Weights at the nominal arm.
  std::vector<double> lt(9 * d.touches), A(9 * d.touches), pos(3 * d.touches);
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
  std::vector<double> S(9 * d.points, 0.0), Sp(3 * d.points, 0.0), first(d.points, -1), C(9 * d.points);
  std::vector<double> centres(3 * d.points);
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
  std::vector<double> x(d.nominal);
  ceres::Problem::Options po;
  ceres::Problem problem(po);
  for (int i = 0; i < d.touches; ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Touch, 3, kParams, 3>(
                                 new Touch(&d.q[i * kJoints], &lt[9 * i])),
                             nullptr, x.data(), &centres[3 * d.point[i]]);
  }
  std::vector<double> weights;
  for (int r = 0; r < d.lengths; ++r) {
    const int a = d.la[r], b = d.lb[r];
    const int ia = (int)first[a], ib = (int)first[b];
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
    const double w = 1.0 / std::sqrt(ul * ul + along(&C[9 * a]) + along(&C[9 * b]));
    weights.push_back(w);
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Length, 1, 3, 3>(new Length(d.ll[r], w)), nullptr,
                             &centres[3 * a], &centres[3 * b]);
  }
  std::vector<int> fixed;
  for (int k = 0; k < kParams; ++k)
    if (d.fixed[k]) fixed.push_back(k);
  problem.SetManifold(x.data(), new ceres::SubsetManifold(kParams, fixed));
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = ceres::DENSE_SCHUR;
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
  run.x = x;
  // The same cost as aacmm's? At aacmm's parameters with the centres at the
  // weighted centroids (what aacmm eliminates them to), Σr² must be its cost.
  {
    const double* xa = d.aacmm.data();
    std::vector<double> P(3 * d.touches), Sa(3 * d.points, 0.0), ca(3 * d.points);
    for (int i = 0; i < d.touches; ++i) {
      Position(xa, &d.q[i * kJoints], &P[3 * i]);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) Sa[3 * d.point[i] + r] += A[9 * i + 3 * r + c] * P[3 * i + c];
    }
    for (int k = 0; k < d.points; ++k)
      for (int r = 0; r < 3; ++r) {
        ca[3 * k + r] = 0;
        for (int c = 0; c < 3; ++c) ca[3 * k + r] += C[9 * k + 3 * r + c] * Sa[3 * k + c];
      }
    double sum = 0;
    for (int i = 0; i < d.touches; ++i) {
      double r[3];
      Touch(&d.q[i * kJoints], &lt[9 * i])(xa, &ca[3 * d.point[i]], r);
      sum += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    }
    for (int r = 0; r < d.lengths; ++r) {
      double v;
      Length(d.ll[r], weights[r])(&ca[3 * d.la[r]], &ca[3 * d.lb[r]], &v);
      sum += v * v;
    }
    run.cost_at_aacmm = sum;
  }
  if (s.termination_type == ceres::FAILURE) std::fprintf(stderr, "ceres: %s\n", s.message.c_str());
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: ceres_lm DIR [REPEATS]\n");
    return 2;
  }
  Data d;
  if (!Read(argv[1], &d)) {
    std::fprintf(stderr, "ceres_lm: cannot read the files in %s\n", argv[1]);
    return 1;
  }
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  Run best = Solve(d);
  for (int r = 1; r < repeats; ++r) {
    Run run = Solve(d);
    if (run.ms_total < best.ms_total) best = run;
  }
  double dmm = 0, drad = 0;
  for (int k = 0; k < kParams; ++k) {
    const double diff = std::fabs(best.x[k] - d.aacmm[k]);
    const bool angle = k >= 2 * kJoints && k < 4 * kJoints;
    (angle ? drad : dmm) = std::max(angle ? drad : dmm, diff);
  }
  // touches ceres_total_ms ceres_solve_ms aacmm_ms ceres_cost aacmm_cost
  // iterations max_dmm max_drad relative difference of the two problems' cost
  // at aacmm's solution
  std::printf("%d %.4f %.4f %.4f %.9e %.9e %d %.3e %.3e %.1e\n", d.touches, best.ms_total, best.ms_solve,
              d.aacmm_ms, best.cost, d.aacmm_cost, best.iterations, dmm, drad,
              std::fabs(best.cost_at_aacmm - d.aacmm_cost) / d.aacmm_cost);
  return 0;
}
