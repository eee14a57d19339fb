#include "circular_coefficients.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace bokeh {

namespace {

// [a, b, A, B] from the README's checked tables (Garcia Table 1 / Niemitalo 2010). Note the sign of
// row 2's B in the 4-component set (-15.227561): the public generator's +15.227561 is wrong.
const std::vector<CircularComponent> kTables[kMaxCircularComponents] = {
    {{0.862325, 1.624835, 0.767583, 1.862321}},
    {{0.886528, 5.268909, 0.411259, -0.548794}, {1.960518, 1.558213, 0.513282, 4.561110}},
    {{2.17649, 5.043495, 1.621035, -2.105439},
     {1.019306, 9.027613, -0.28086, -0.162882},
     {2.81511, 1.597273, -0.366471, 10.300301}},
    {{4.338459, 1.553635, -5.767909, 46.164397},
     {3.839993, 4.693183, 9.795391, -15.227561},
     {2.791880, 8.178137, -3.048324, 0.302959},
     {1.342190, 12.328289, 0.010001, 0.244650}},
    {{4.892608, 1.685979, -22.356787, 85.91246},
     {4.71187, 4.998496, 35.918936, -28.875618},
     {4.052795, 8.244168, -13.212253, -1.578428},
     {2.929212, 11.900859, 0.507991, 1.816328},
     {1.512961, 16.116382, 0.138051, -0.01}},
    {{5.143778, 2.079813, -82.326596, 111.231024},
     {5.612426, 6.153387, 113.878661, 58.004879},
     {5.982921, 9.802895, 39.479083, -162.028887},
     {6.505167, 11.059237, -71.286026, 95.027069},
     {3.869579, 14.81052, 1.405746, -3.704914},
     {2.201904, 19.032909, -0.152784, -0.107988}},
};

void check_components(int components) {
  if (components < 1 || components > kMaxCircularComponents)
    throw std::invalid_argument("circular filter components must be in [1, 6], got " + std::to_string(components));
}

CircularKernel build_kernel(int components, int radius_px, double u_per_px) {
  CircularKernel k;
  k.components = components;
  k.radius_px = radius_px;
  k.u_per_px = u_per_px;
  // The 2D sum of F(x) F(y) over the tap square is (sum_x F(x))^2, so the normaliser needs only the
  // 1D sums P_c. Summed from the float taps the filter actually applies, so the applied kernel sums to 1.
  double sum_2d = 0.0;
  for (const CircularComponent& c : circular_components(components)) {
    std::vector<std::complex<float>> taps;
    std::complex<double> p = 0.0;
    for (int x = -radius_px; x <= radius_px; ++x) {
      const double u2 = (x * u_per_px) * (x * u_per_px);
      const std::complex<float> f(std::polar(std::exp(-c.a * u2), c.b * u2));
      taps.push_back(f);
      p += std::complex<double>(f);
    }
    const std::complex<double> p2 = p * p;
    sum_2d += c.A * p2.real() + c.B * p2.imag();
    k.taps.push_back(std::move(taps));
  }
  k.normalisation = sum_2d;
  for (const CircularComponent& c : circular_components(components)) {
    k.weight_real.push_back(static_cast<float>(c.A / sum_2d));
    k.weight_imag.push_back(static_cast<float>(c.B / sum_2d));
  }
  return k;
}

}  // namespace

const std::vector<CircularComponent>& circular_components(int components) {
  check_components(components);
  return kTables[components - 1];
}

double circular_scale(int components) {
  check_components(components);
  return components == 1 ? 1.4 : 1.2;
}

double circular_radial_profile(int components, double u) {
  const double u2 = u * u;
  double k = 0.0;
  for (const CircularComponent& c : circular_components(components))
    k += std::exp(-c.a * u2) * (c.A * std::cos(c.b * u2) + c.B * std::sin(c.b * u2));
  return k;
}

CircularKernel make_circular_kernel(int components, int radius_px) {
  if (radius_px < 1) throw std::invalid_argument("circular kernel radius must be >= 1 px, got " + std::to_string(radius_px));
  return build_kernel(components, radius_px, circular_scale(components) / radius_px);
}

CircularKernel make_circular_kernel_for_disc(int components, double disc_radius_px) {
  if (!(disc_radius_px > 0.0) || !std::isfinite(disc_radius_px))
    throw std::invalid_argument("circular disc radius must be finite and > 0 px, got " + std::to_string(disc_radius_px));
  const double u_per_px = kDiscEdgeU / disc_radius_px;
  // The small epsilon keeps an exact multiple (e.g. disc 11 px, s 1.2 -> R 12) from rounding up.
  const int radius_px = std::max(1, static_cast<int>(std::ceil(circular_scale(components) / u_per_px - 1e-9)));
  return build_kernel(components, radius_px, u_per_px);
}

double kernel_2d(const CircularKernel& k, int x_px, int y_px) {
  if (std::abs(x_px) > k.radius_px || std::abs(y_px) > k.radius_px) return 0.0;
  double value = 0.0;
  for (int c = 0; c < k.components; ++c) {
    const std::complex<double> p = std::complex<double>(k.taps[c][x_px + k.radius_px]) *
                                   std::complex<double>(k.taps[c][y_px + k.radius_px]);
    value += k.weight_real[c] * p.real() + k.weight_imag[c] * p.imag();
  }
  return value;
}

RippleReport measure_ripple(int components, double passband_end_u, double stopband_start_u, double max_u,
                            int samples) {
  check_components(components);
  if (samples < 2 || !(max_u > 0.0) || !(passband_end_u <= stopband_start_u))
    throw std::invalid_argument("measure_ripple needs samples >= 2, max_u > 0 and passband end <= stopband start");
  RippleReport report;
  report.profile.reserve(samples);
  for (int i = 0; i < samples; ++i) {
    const double u = max_u * i / (samples - 1);
    const double k = circular_radial_profile(components, u);
    report.profile.emplace_back(u / kDiscEdgeU, k);
    if (u <= passband_end_u) report.max_ripple_passband = std::max(report.max_ripple_passband, std::abs(k - 1.0));
    if (u >= stopband_start_u) report.max_ripple_stopband = std::max(report.max_ripple_stopband, std::abs(k));
  }
  return report;
}

}  // namespace bokeh
