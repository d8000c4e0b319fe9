// Stress concentration factor of a shoulder fillet (issue 33, docs/notch.md).
#pragma once

namespace osteon {

/// Elastic stress concentration factor Kt of a stepped round bar with a shoulder fillet in
/// bending (diameters D > d, fillet radius r; all mm): Kt = C1 + C2 (2h/D) + C3 (2h/D)^2 +
/// C4 (2h/D)^3, h = (D - d) / 2, each C_i = a + b sqrt(h/r) + c h/r, two ranges of h/r split at 2.
/// Coefficients: Roark's Formulas for Stress and Strain, 7th ed., Table 17.1 ("square shoulder
/// with fillet in circular shaft", elastic stress, bending), the fit of Peterson's charts
/// (Pilkey & Pilkey, Peterson's Stress Concentration Factors, 3rd ed., Chart 3.11). Valid
/// 0.25 <= h/r <= 20; outside it the result is clamped on the safe side: h/r < 0.25 is
/// evaluated at 0.25 (Kt grows with h/r), and a sharper corner, h/r > 20, extrapolates Neuber's
/// law Kt - 1 ~ sqrt(h/r) from h/r = 20. That fit rests on photoelastic data that read low at
/// sharp fillets, so the larger of it and the finite-element fit of Tipton, Sorem & Rolovic
/// (ASME J. Mech. Design 118 (1996) 321-327), Kt = 0.632 + 0.377 (D/d)^-4.4 + sqrt(a / b / (r/d)),
/// a = -0.14 - 0.363 (D/d)^2 + 0.503 (D/d)^4, b = 1 - 2.39 (D/d)^2 + 3.368 (D/d)^4, is returned.
/// D/d is capped at kMaxStepRatio (the fit saturates; the largest Kt over D/d <= the cap is
/// used). Returns 1 for D <= d or a non-finite input.
double shoulder_fillet_kt(double big_diameter, double small_diameter, double radius);

/// D/d beyond which a step counts as this ratio (the study's and the charts' top, docs/notch.md).
constexpr double kMaxStepRatio = 3.0;
/// Neighbouring sections whose equivalent radii differ by this factor or more are a step.
constexpr double kStepRatio = 1.1;

}  // namespace osteon
