#pragma once
// Circular separable filter coefficients (Niemitalo 2010; Garcia, "Circular Separable Convolution
// Depth of Field", GDC 2018): sums of complex Gaussians F_c(u) = exp(-a u^2) (cos(b u^2) + i sin(b u^2))
// whose 2D products depend on r^2 = x^2 + y^2 only, so a 2D disc blur runs as two 1D passes.
//
// Radial profile. F_c(x) F_c(y) = exp(-a r^2) (cos(b r^2) + i sin(b r^2)), so the 2D kernel is
//   K(r) = sum_c exp(-a_c r^2) (A_c cos(b_c r^2) + B_c sin(b_c r^2)).
// With the published A, B as they stand (no rescaling) K is an equiripple fit of a disc of height 1:
// passband u in [0, 1], transition band (1, 1.2), stopband u >= 1.2; K crosses 1/2 at u = 1.100-1.103.
// The disc edge is therefore at u = 1.1 (kDiscEdgeU), not at u = s: with the published mapping
// u = s x / R the visible disc has radius 1.1 R / s (0.79 R for 1 component, 0.92 R for 2..6).
// Measured max |K - 1| (passband) / max |K| (stopband), vs the published max ripple:
//   1: 0.2324/0.2326 (0.232)  2: 0.0758/0.0773 (0.076)  3: 0.0269/0.0275 (0.027)
//   4: 0.0109/0.0109 (0.011)  5: 0.0041/0.0041 (0.0041) 6: 0.0020/0.0019 (0.0020)
// i.e. within 2% of the published figures (the tables are rounded to 6 decimals). Rescaling K so the
// passband mean is 1 does worse (1 component: 0.248), so the tables are already height-1 normalised.
#include <complex>
#include <utility>
#include <vector>

namespace bokeh {

struct CircularComponent {
  double a;  // decay of the Gaussian envelope
  double b;  // phase rate
  double A;  // weight of the real part
  double B;  // weight of the imaginary part
};

inline constexpr double kPassbandEndU = 1.0;
inline constexpr double kStopbandStartU = 1.2;
inline constexpr double kDiscEdgeU = 1.1;  // centre of the transition band: where K crosses 1/2
inline constexpr int kMaxCircularComponents = 6;

// The published [a, b, A, B] rows for 1..6 components; throws std::invalid_argument otherwise.
const std::vector<CircularComponent>& circular_components(int components);
// Kernel extent in u: taps cover u in [-s, s]. 1.4 for one component (its slow tail), 1.2 for more.
double circular_scale(int components);
// The published (height-1 disc) radial profile K(u) above.
double circular_radial_profile(int components, double u);

// A sampled kernel. Normalisation: the published A, B are divided by `normalisation`, the sum over
// all taps (x, y) in [-R, R]^2 of the unnormalised 2D kernel, so the 2D kernel sums to 1; the taps
// stay the exact F_c values (|tap| <= 1). kernel_2d(k, x, y) * normalisation is K(u(x, y)).
struct CircularKernel {
  int components = 0;
  int radius_px = 0;        // taps at x in [-radius_px, radius_px]
  double u_per_px = 0.0;    // tap x sits at u = x * u_per_px
  double normalisation = 0.0;
  std::vector<std::vector<std::complex<float>>> taps;  // [component][x + radius_px]
  std::vector<float> weight_real;                      // A_c / normalisation
  std::vector<float> weight_imag;                      // B_c / normalisation

  int tap_count() const { return 2 * radius_px + 1; }
  double disc_radius_px() const { return kDiscEdgeU / u_per_px; }
};

// The published mapping: integer kernel radius R, u = s x / R (disc radius 1.1 R / s px).
CircularKernel make_circular_kernel(int components, int radius_px);
// A kernel whose disc edge (u = 1.1) lands at disc_radius_px: u = 1.1 x / disc_radius_px, and
// R = ceil(s * disc_radius_px / 1.1) so the taps still cover u in [-s, s].
CircularKernel make_circular_kernel_for_disc(int components, double disc_radius_px);

// The normalised 2D kernel at tap (x, y); 0 outside [-R, R]^2.
double kernel_2d(const CircularKernel& kernel, int x_px, int y_px);

struct RippleReport {
  double max_ripple_passband = 0.0;  // max |K(u) - 1| for u <= passband_end_u
  double max_ripple_stopband = 0.0;  // max |K(u)| for u >= stopband_start_u
  // (r / disc radius, K) with r / disc radius = u / kDiscEdgeU; K in the published normalisation,
  // where the ideal disc has height 1 (see the header comment for why not the passband mean).
  std::vector<std::pair<double, double>> profile;
};

// Samples the continuous radial profile on u in [0, max_u] (`samples` points, evenly spaced) and
// compares it with the unit-height disc outside the transition band (passband_end_u, stopband_start_u).
RippleReport measure_ripple(int components, double passband_end_u = kPassbandEndU,
                            double stopband_start_u = kStopbandStartU, double max_u = 4.0, int samples = 8001);

}  // namespace bokeh
