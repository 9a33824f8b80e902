// Step 2's scalar root-finder (DESIGN.md §3 "Root-finding"): a safeguarded hybrid of
// Newton-Raphson and regula falsi with the Illinois modification, warm-started.
//
// Solves g(s) = 0 for s in [-s_max, s_max], where g > 0 means "inside" so the root lies
// towards +s (outward along the projection direction). Starting at s0: if |g(s0)| < tol it
// returns after one evaluation. Otherwise it takes Newton steps towards the root (or
// doubling steps when the derivative points the wrong way) until the sign changes, then
// keeps the root bracketed: a Newton step that leaves the bracket, or a vanishing
// derivative, is replaced by an Illinois false-position step, and bisection breaks stalls.
// Stops at |g| < tol, where the Newton step |g / g'| is below step_tol, or when the
// bracket is narrower than step_tol; a Newton step below final_step is taken without
// evaluating again (unless a known point of the other sign lies before its end). Header-only
// so the per-vertex function inlines; allocates nothing.
#pragma once

#include <algorithm>
#include <cmath>

namespace vistel {

struct RootOptions {
  float tolerance = 1e-6f;       // |g| below this is a root (field units)
  float step_tolerance = 1e-6f;  // a step below this ends the search (metres); so does a
                                 // Newton step |g / g'| below it (float positions a metre
                                 // from the origin carry ~1e-7 m of rounding, i.e. |g| of
                                 // ~1e-5 in a steep field, even on the surface)
  float first_step = 1e-3f;      // smallest search step before bracketing (metres)
  float final_step = 1e-4f;      // a Newton step shorter than this (metres) is taken without
                                 // evaluating again: its error is about g''/(2 g') times its
                                 // square, well below step_tolerance in a field of centimetre
                                 // features
  int max_iterations = 40;
};

struct RootResult {
  float s = 0.0f;
  int iterations = 0;         // evaluations after the first
  bool final_newton = false;  // ended with a Newton step shorter than final_step, not
                              // evaluated (an iteration without an evaluation)
  bool found = false;
};

// eval(s, &dg) returns g(s) and writes g'(s) (may be 0 or non-finite: then unused).
// The overload with (g0, dg0) reuses an evaluation at s0 the caller already made.
template <typename Eval>
RootResult findRoot(Eval&& eval, float s0, float g0, float dg0, float s_max,
                    const RootOptions& opt) {
  RootResult r;
  float dg = dg0;
  float g = g0;
  float s = s0;
  r.s = s0;
  const auto converged = [&opt](float gv, float dgv) {
    return std::abs(gv) < opt.tolerance ||
           (std::isfinite(dgv) && std::abs(gv) < opt.step_tolerance * std::abs(dgv));
  };
  if (converged(g, dg)) {
    r.found = true;
    return r;
  }
  // Bracket ends: pos has g > 0, neg has g < 0 (values possibly Illinois-scaled).
  bool have_pos = g > 0.0f;
  bool have_neg = g < 0.0f;
  float s_pos = s, g_pos = g, s_neg = s, g_neg = g;
  // The last Newton step from (s, g, dg) when it is short, unless a known point of the other
  // sign lies before its end (a kink may lie between).
  const auto final_newton = [&]() {
    if (!std::isfinite(dg) || !(std::abs(g) < opt.final_step * std::abs(dg))) return false;
    const float s_newton = s - g / dg;
    const bool other = g > 0.0f ? have_neg : have_pos;
    const float s_other = g > 0.0f ? s_neg : s_pos;
    if (other && !((s_newton - s) * (s_other - s_newton) > 0.0f)) return false;
    r.s = std::clamp(s_newton, -s_max, s_max);
    r.final_newton = true;
    r.found = true;
    return true;
  };
  if (final_newton()) return r;
  int last_side = 0;
  bool false_position = false;
  float step = 0.0f;  // last search step (before bracketing)
  // Bracket widths of recent iterations (for the bisection safeguard).
  int width_count = 0;
  float width_two_ago = INFINITY;
  float width_one_ago = INFINITY;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    const bool newton_ok = std::isfinite(dg) && dg != 0.0f;
    float s_new = newton_ok ? s - g / dg : s;
    if (have_pos && have_neg) {
      // Bracketed: Newton when it stays strictly inside, else Illinois false position;
      // bisection whenever two steps have not halved the bracket (a kink or a near-step
      // in g would otherwise stall either method).
      const float lo = std::min(s_pos, s_neg);
      const float hi = std::max(s_pos, s_neg);
      const float width = hi - lo;
      const bool stalled = width_count >= 2 && width > 0.5f * width_two_ago;
      if (stalled) {
        s_new = 0.5f * (lo + hi);
        false_position = false;
      } else if (newton_ok && s_new > lo && s_new < hi) {
        false_position = false;
      } else {
        s_new = (s_neg * g_pos - s_pos * g_neg) / (g_pos - g_neg);
        if (!(s_new > lo && s_new < hi)) s_new = 0.5f * (lo + hi);
        false_position = true;
      }
      if (stalled) width_count = 0;
      width_two_ago = width_one_ago;
      width_one_ago = width;
      ++width_count;
    } else {
      // Searching: go outward when inside (g > 0), inward when outside; take the Newton
      // step when it agrees, else a step that doubles each time.
      const float dir = g > 0.0f ? 1.0f : -1.0f;
      float h = s_new - s;
      const float h_min = std::max(opt.first_step, 2.0f * step);
      if (!newton_ok || h * dir <= 0.0f) h = dir * h_min;
      h = dir * std::min(std::abs(h), std::max(h_min, 0.25f * s_max));
      s_new = std::clamp(s + h, -s_max, s_max);
      if (s_new == s) return r;  // at the limit with no sign change: no root within reach
      step = std::abs(s_new - s);
    }
    float dg_new = 0.0f;
    const float g_new = eval(s_new, &dg_new);
    r.iterations = it;
    s = s_new;
    g = g_new;
    dg = dg_new;
    r.s = s;
    if (converged(g, dg)) {
      r.found = true;
      return r;
    }
    if (final_newton()) return r;
    // Update the bracket (Illinois: after two false-position hits on the same side, halve
    // the kept end's value).
    if (g > 0.0f) {
      if (false_position && last_side == 1 && have_neg) g_neg *= 0.5f;
      s_pos = s;
      g_pos = g;
      have_pos = true;
      last_side = 1;
    } else {
      if (false_position && last_side == -1 && have_pos) g_pos *= 0.5f;
      s_neg = s;
      g_neg = g;
      have_neg = true;
      last_side = -1;
    }
    if (have_pos && have_neg && std::abs(s_pos - s_neg) < opt.step_tolerance) {
      r.found = true;
      return r;
    }
  }
  return r;
}

template <typename Eval>
RootResult findRoot(Eval&& eval, float s0, float s_max, const RootOptions& opt) {
  float dg0 = 0.0f;
  const float g0 = eval(s0, &dg0);
  return findRoot(eval, s0, g0, dg0, s_max, opt);
}

}  // namespace vistel
