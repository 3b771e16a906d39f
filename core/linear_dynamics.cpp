#include "core/linear_dynamics.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rths::core {

LinearBlock series(const LinearBlock& first, const LinearBlock& second) {
  const int n1 = first.states(), n2 = second.states();
  LinearBlock out = zero_block(n1 + n2, second.d * first.d);
  if (n1 > 0) {
    out.a.topLeftCorner(n1, n1) = first.a;
    out.b.head(n1) = first.b;
    out.c.head(n1) = second.d * first.c;
  }
  if (n2 > 0) {
    out.a.bottomRightCorner(n2, n2) = second.a;
    if (n1 > 0) out.a.bottomLeftCorner(n2, n1) = second.b * first.c;
    out.b.tail(n2) = second.b * first.d;
    out.c.tail(n2) = second.c;
  }
  return out;
}

LinearBlock zero_block(int states, double d) {
  LinearBlock block;
  block.a = Mat::Zero(states, states);
  block.b = Vec::Zero(states);
  block.c = Eigen::RowVectorXd::Zero(states);
  block.d = d;
  return block;
}

LinearBlock gain_block(double gain) { return zero_block(0, gain); }

LinearBlock fir_block(double d, const std::vector<double>& taps) {
  const int n = static_cast<int>(taps.size());
  LinearBlock f = gain_block(d);
  if (n == 0) return f;
  f.a = Mat::Zero(n, n);
  for (int i = 1; i < n; ++i) f.a(i, i - 1) = 1.0;
  f.b = Vec::Unit(n, 0);
  f.c = Eigen::RowVectorXd::Map(taps.data(), n);
  return f;
}

LinearBlock shift_block(double delay, double dt) {
  if (!(delay >= 0.0) || !(dt > 0.0))
    throw std::invalid_argument("stability: shift needs delay >= 0 and dt > 0");
  const double steps = delay / dt;
  int n = static_cast<int>(std::floor(steps + 1e-9));
  double w = steps - n;
  if (w < 1e-9) w = 0.0;
  std::vector<double> taps(static_cast<std::size_t>(w > 0.0 ? n + 1 : n), 0.0);
  double d = 0.0;
  if (n == 0)
    d = 1.0 - w;
  else
    taps[static_cast<std::size_t>(n) - 1] += 1.0 - w;
  if (w > 0.0) taps[static_cast<std::size_t>(n)] += w;
  return fir_block(d, taps);
}

LinearBlock direct_form_block(const std::vector<double>& b, const std::vector<double>& a) {
  const int n = static_cast<int>(a.size()) - 1;
  LinearBlock f = gain_block(b[0]);
  if (n == 0) return f;
  f.a = Mat::Zero(n, n);
  f.b = Vec::Zero(n);
  f.c = Eigen::RowVectorXd::Unit(n, 0);
  for (int i = 0; i < n; ++i) {
    const auto next = static_cast<std::size_t>(i) + 1;
    f.a(i, 0) = -a[next];
    if (i + 1 < n) f.a(i, i + 1) = 1.0;
    f.b[i] = b[next] - a[next] * b[0];
  }
  return f;
}

std::complex<double> response_at(const LinearBlock& block, std::complex<double> z) {
  const int n = block.states();
  if (n == 0) return block.d;
  const Eigen::MatrixXcd resolvent =
      z * Eigen::MatrixXcd::Identity(n, n) - block.a.cast<std::complex<double>>();
  const Eigen::VectorXcd x = resolvent.partialPivLu().solve(block.b.cast<std::complex<double>>());
  return (block.c.cast<std::complex<double>>() * x)(0) + block.d;
}

std::complex<double> polynomial_at(const std::vector<double>& p, std::complex<double> s) {
  std::complex<double> value = 0.0;
  for (double c : p) value = value * s + c;
  return value;
}

std::vector<double> polynomial_multiply(const std::vector<double>& a,
                                        const std::vector<double>& b) {
  if (a.empty() || b.empty()) return {};
  std::vector<double> out(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

std::vector<double> trimmed(std::vector<double> p) {
  while (p.size() > 1 && p.front() == 0.0) p.erase(p.begin());
  return p;
}

void PlantModel::append(const std::vector<double>& num, const std::vector<double>& den) {
  numerator = polynomial_multiply(numerator, num);
  denominator = polynomial_multiply(denominator, den);
}

void PlantModel::append(const PlantModel& other) {
  gain *= other.gain;
  delay += other.delay;
  append(other.numerator, other.denominator);
}

std::string PlantModel::describe() const {
  std::ostringstream out;
  out << "plant(delay " << delay * 1e3 << " ms, gain " << gain << ", order "
      << trimmed(denominator).size() - 1 << "/" << trimmed(numerator).size() - 1 << ")";
  return out.str();
}

std::complex<double> PlantModel::at(double omega) const {
  const std::complex<double> s(0.0, omega);
  return gain * std::exp(-s * delay) * polynomial_at(numerator, s) / polynomial_at(denominator, s);
}

}  // namespace rths::core
