// Helpers shared by the soft-body samples: drawing, grabbing, panel rows, stability.
#include "soft_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <imgui.h>

#include "camera.h"
#include "pba/lab.h"

namespace pba::app {

namespace {

Color mix(Color a, Color b, float u) {
  return Color{a.r + (b.r - a.r) * u, a.g + (b.g - a.g) * u, a.b + (b.b - a.b) * u, a.a};
}

}  // namespace

// ---------------------------------------------------------------------------------------
// drawing

std::span<const float> SoftPainter::ParticleStrain(const SoftBody& body) {
  // the largest strain of the intact stretch constraints at each particle
  strain_.assign(body.size(), 0.0f);
  const auto xs = body.xs(), ys = body.ys(), zs = body.zs();
  for (std::size_t k = 0; k < body.constraint_count(); ++k) {
    const SoftConstraint c = body.constraint(k);
    if (c.broken || c.kind != SoftConstraintKind::Stretch) continue;
    const float dx = xs[c.b] - xs[c.a], dy = ys[c.b] - ys[c.a], dz = zs[c.b] - zs[c.a];
    const float e = std::abs(std::sqrt(dx * dx + dy * dy + dz * dz) / static_cast<float>(c.rest_length) - 1.0f);
    strain_[c.a] = std::max(strain_[c.a], e);
    strain_[c.b] = std::max(strain_[c.b], e);
  }
  return strain_;
}

void SoftPainter::DrawSurface(Renderer& r, std::span<const Vec3f> pos, std::span<const SoftTriangle> tris, Color color,
                              std::span<const Color> particle_colors, std::span<const float> strain,
                              double strain_scale) {
  // area-weighted vertex normals from the (counter-clockwise) triangles
  nrm_.assign(pos.size(), Vec3f(0));
  for (const SoftTriangle& t : tris) {
    const Vec3f n = glm::cross(pos[t.b] - pos[t.a], pos[t.c] - pos[t.a]);
    nrm_[t.a] += n, nrm_[t.b] += n, nrm_[t.c] += n;
  }
  // colour per corner: the particle's (or the base), tinted towards red by strain
  const float inv_scale = strain_scale > 0 ? static_cast<float>(1.0 / strain_scale) : 0.0f;
  auto corner = [&](std::uint32_t i) {
    Color c = particle_colors.size() == pos.size() ? particle_colors[i] : color;
    if (!strain.empty()) c = mix(c, soft_colors::strain, std::min(1.0f, strain[i] * inv_scale));
    return TriangleCorner{Vec3(pos[i]), Vec3(nrm_[i]), c};
  };
  for (const SoftTriangle& t : tris) r.triangle(corner(t.a), corner(t.b), corner(t.c));
}

void SoftPainter::Draw(Renderer& r, const SoftBody& body, const SoftView& view, Color color,
                       std::span<const Color> particle_colors, const DrawFlags& flags) {
  // the surface, from a copy of the positions
  if (view.surface && !body.triangles().empty()) {
    pos_.resize(body.size());
    body.copy_positions(pos_);
    std::span<const float> strain;
    if (view.strain) strain = ParticleStrain(body);
    DrawSurface(r, pos_, body.triangles(), color, particle_colors, strain, view.strain_scale);
  }
  // edges and pins through the library's own drawing
  SoftDrawOptions o;
  o.triangles = false;
  o.edges = view.edges || view.all_edges;
  o.all_edges = view.all_edges;
  o.strain_colors = view.strain;
  o.strain_scale = view.strain_scale;
  o.pins = view.pins;
  o.color = view.surface ? Color{0.08f, 0.09f, 0.11f, 0.55f} : color;
  if (o.edges || o.pins) body.draw(r, flags, o);
}

// ---------------------------------------------------------------------------------------
// grabbing

bool SoftGrab::Press(std::span<SoftBody* const> bodies, const Camera& camera, const Vec3& o, const Vec3& d) {
  // pick radius: ~14 pixels at the orbit target's depth
  const double h = std::max(ImGui::GetIO().DisplaySize.y, 1.0f);
  const double radius = std::max(0.02, 14.0 * 2.0 * camera.distance * std::tan(0.5 * camera.fov_y) / h);
  int best = -1;
  std::uint32_t best_p = kNoParticle;
  double best_s = 1e300;
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    if (!bodies[k] || bodies[k]->failed() || bodies[k]->size() == 0) continue;
    const std::uint32_t p = bodies[k]->nearest_particle(o, d, radius);
    if (p == kNoParticle) continue;
    const double s = glm::dot(bodies[k]->position(p) - o, d);
    if (s < best_s) best = static_cast<int>(k), best_p = p, best_s = s;
  }
  if (best < 0) return false;
  // the drag plane faces the camera and goes through the particle
  const Vec3 p = bodies[static_cast<std::size_t>(best)]->position(best_p);
  plane_n_ = glm::normalize(Vec3(camera.target) - Vec3(camera.eye()));
  const double den = glm::dot(d, plane_n_);
  const Vec3 hit = std::abs(den) < 1e-9 ? p : o + d * (glm::dot(p - o, plane_n_) / den);
  offset_ = p - hit;
  target_ = p;
  body_ = best;
  bodies[static_cast<std::size_t>(best)]->grab(best_p, target_);
  return true;
}

void SoftGrab::Move(std::span<SoftBody* const> bodies, const Vec3& o, const Vec3& d) {
  if (body_ < 0) return;
  // the release happened over a panel
  if (!ImGui::GetIO().MouseDown[0]) {
    Release(bodies);
    return;
  }
  const double den = glm::dot(d, plane_n_);
  if (std::abs(den) < 1e-6) return;
  SoftBody* held = static_cast<std::size_t>(body_) < bodies.size() ? bodies[static_cast<std::size_t>(body_)] : nullptr;
  if (!held) {  // the body went away (stopped or rebuilt)
    body_ = -1;
    return;
  }
  SoftBody& b = *held;
  if (b.grabbed() == kNoParticle) {  // torn free or released by the body
    body_ = -1;
    return;
  }
  const Vec3 p0 = target_ - offset_;
  target_ = o + d * (glm::dot(p0 - o, plane_n_) / den) + offset_;
  b.move_grab(target_);
}

void SoftGrab::Release(std::span<SoftBody* const> bodies) {
  if (body_ >= 0 && static_cast<std::size_t>(body_) < bodies.size() && bodies[static_cast<std::size_t>(body_)])
    bodies[static_cast<std::size_t>(body_)]->release();
  body_ = -1;
}

void SoftGrab::Draw(Renderer& r, std::span<SoftBody* const> bodies) const {
  if (body_ < 0 || static_cast<std::size_t>(body_) >= bodies.size() || !bodies[static_cast<std::size_t>(body_)]) return;
  const SoftBody& b = *bodies[static_cast<std::size_t>(body_)];
  const std::uint32_t g = b.grabbed();
  if (g == kNoParticle) return;
  r.line(b.position(g), target_, soft_colors::grab, 2.0f);
  r.sphere(target_, 0.025, soft_colors::grab);
}

// ---------------------------------------------------------------------------------------
// panel rows

void SolverPanel::refresh(const SoftBodyDef& def, const SoftBody& body) {
  const double k[4] = {def.stretch_stiffness, def.shear_stiffness, def.bend_stiffness, def.volume_stiffness};
  if (omega_ >= 0 && body_ == &body && size_ == body.size() && std::equal(k, k + 4, k_)) return;
  omega_ = MaxAngularFrequency(body, def);
  std::copy(k, k + 4, k_);
  body_ = &body;
  size_ = body.size();
}

bool SolverPanel::Draw(SoftBodyDef& def, const SoftBody& body, double dt) {
  bool changed = false;
  // the solver
  int solver = def.solver == SoftSolver::Xpbd ? 0 : 1;
  ImGui::SetNextItemWidth(-110);
  if (ImGui::Combo("solver", &solver, "XPBD\0mass-spring\0")) {
    changed = true;
    // a mass-spring network gets enough substeps to be stable with its integrator
    if (solver == 1) UseMassSpring(def, body, dt);
    else def.solver = SoftSolver::Xpbd;
  }
  const bool has_tets = !body.tets().empty();
  if (def.solver == SoftSolver::Xpbd) {
    // substeps, iterations, tethers, compliances
    changed |= SubstepControls(def);
    if (body.pins().size() > 0) {
      changed |= ImGui::Checkbox("long-range attachments", &def.tethers);
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip("tethers (Kim et al. 2012): no particle may drift further from its nearest pin than it was "
                          "built; off while the cloth can tear");
    }
    changed |= ComplianceSlider("stretch", &def.stretch_compliance, 1e-8, 1e-1);
    if (!has_tets) {
      changed |= ComplianceSlider("shear", &def.shear_compliance, 1e-8, 1e-1);
      changed |= ComplianceSlider("bend", &def.bend_compliance, 1e-6, 1e0);
    } else {
      changed |= ComplianceSlider("volume", &def.volume_compliance, 1e-9, 1e-2, "m^5/N");
    }
    return changed;
  }
  // the integrator (implicit Euler's dense solve is limited to 512 particles)
  ImGui::SetNextItemWidth(-110);
  if (ImGui::BeginCombo("integrator", std::string(label(def.method)).c_str())) {
    for (Method m : kAllMethods) {
      const bool too_big = m == Method::ImplicitEuler && body.size() > 512;
      ImGui::BeginDisabled(too_big);
      if (ImGui::Selectable(std::string(label(m)).c_str(), m == def.method)) {
        def.method = m;
        changed = true;
      }
      ImGui::EndDisabled();
      if (too_big && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
        ImGui::SetTooltip("a dense Newton solve: at most 512 particles");
    }
    ImGui::EndCombo();
  }
  ImGui::SetNextItemWidth(-110);
  changed |= ImGui::SliderInt("substeps", &def.substeps, 1, 400, "%d", ImGuiSliderFlags_Logarithmic);
  def.substeps = std::clamp(def.substeps, 1, 10000);
  // stiffnesses and damping
  auto stiffness = [&](const char* name, double* k, float lo, float hi, const char* fmt) {
    float v = static_cast<float>(*k);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat(name, &v, lo, hi, fmt, ImGuiSliderFlags_Logarithmic)) {
      *k = v;
      changed = true;
    }
  };
  stiffness("stretch k", &def.stretch_stiffness, 1.0f, 1e5f, "%.0f N/m");
  if (!has_tets) {
    stiffness("shear k", &def.shear_stiffness, 1.0f, 1e5f, "%.0f N/m");
    stiffness("bend k", &def.bend_stiffness, 0.1f, 1e4f, "%.1f N/m");
  } else {
    stiffness("volume k", &def.volume_stiffness, 1.0f, 1e9f, "%.0f N/m^5");
  }
  float c = static_cast<float>(def.spring_damping);
  ImGui::SetNextItemWidth(-110);
  if (ImGui::SliderFloat("spring damping", &c, 0.0f, 1.0f, "%.3f N s/m")) {
    def.spring_damping = c;
    changed = true;
  }
  // the explicit stability check
  refresh(def, body);
  const double h = dt / def.substeps, lim = StabilityLimit(def.method);
  if (lim <= 0) {
    ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "explicit Euler gains energy at every step");
  } else if (std::isfinite(lim)) {
    const bool ok = omega_ * h < lim;
    ImGui::TextColored(ok ? ImVec4(0.6f, 0.85f, 0.6f, 1) : ImVec4(1, 0.45f, 0.4f, 1), "omega_max h = %.2f (limit %.2f)",
                       omega_ * h, lim);
    ImGui::TextDisabled("omega_max = %.0f rad/s, h = %.3f ms", omega_, 1e3 * h);
  } else {
    ImGui::TextDisabled("implicit Euler: stable at any step (and damped)");
  }
  return changed;
}

void UseMassSpring(SoftBodyDef& def, const SoftBody& body, double dt) {
  def.solver = SoftSolver::MassSpring;
  if (def.method == Method::ImplicitEuler && body.size() > 512) def.method = Method::SemiImplicitEuler;
  const double lim = StabilityLimit(def.method);
  if (lim > 0 && std::isfinite(lim)) {
    const double omega = MaxAngularFrequency(body, def);
    def.substeps = std::clamp(static_cast<int>(std::ceil(omega * dt / (0.8 * lim))), def.substeps, 400);
  }
}

SoftSolver SolverOption(const SampleContext& ctx, SoftSolver fallback) {
  const std::string v = ctx.option("solver", "");
  if (v.empty()) return fallback;
  if (v == "xpbd") return SoftSolver::Xpbd;
  if (v == "mass-spring") return SoftSolver::MassSpring;
  throw Error("--option solver=" + v + ": expected xpbd or mass-spring");
}

SoftBodyDef XpbdCloth(int substeps, double damping) {
  SoftBodyDef d;
  d.solver = SoftSolver::Xpbd;
  d.substeps = substeps;
  d.iterations = 1;
  d.bend_compliance = 1e-3;
  d.damping = damping;
  return d;
}

void PlotHistory::Clear() {
  t_.clear();
  for (auto& y : y_) y.clear();
}

void PlotHistory::Push(double t, std::initializer_list<double> values) {
  // append, then drop the oldest quarter once the front is older than `keep`
  t_.push_back(static_cast<float>(t));
  auto v = values.begin();
  for (auto& y : y_) y.push_back(v != values.end() ? static_cast<float>(*v++) : 0.0f);
  if (t_.size() > 64 && t_.front() < t - keep_) {
    const auto drop = static_cast<std::ptrdiff_t>(t_.size() / 4);
    t_.erase(t_.begin(), t_.begin() + drop);
    for (auto& y : y_) y.erase(y.begin(), y.begin() + drop);
  }
}

void PlotHistory::Plot(const char* id, std::span<const Color> colors, const PlotAxes& axes, float height) const {
  std::vector<PlotSeries> s;
  for (std::size_t k = 0; k < y_.size() && k < colors.size() && !t_.empty(); ++k) {
    PlotSeries p;
    p.x = t_.data(), p.y = y_[k].data(), p.count = static_cast<int>(t_.size());
    p.color = colors[k], p.width = 2.0f;
    s.push_back(p);
  }
  LinePlot(id, s, axes, height);
}

void SoftSample::Mouse(int button, bool down, const Vec3& o, const Vec3& d) {
  if (button != 0) return;
  if (!down) {
    grab_.Release(Bodies());
    return;
  }
  if (grab_.Press(Bodies(), *ctx_.camera, o, d)) Grabbed();
}

void OneBodySample::SolverFromOption() {
  if (SolverOption(ctx_, SoftSolver::Xpbd) != SoftSolver::MassSpring) return;
  UseMassSpring(def_, body_, ctx_.settings.stepper.fixed_dt);
  body_.settings() = def_;
}

bool SubstepControls(SoftBodyDef& def, int max_substeps, int max_iterations) {
  bool changed = false;
  ImGui::SetNextItemWidth(-110);
  changed |= ImGui::SliderInt("substeps", &def.substeps, 1, max_substeps, "%d", ImGuiSliderFlags_Logarithmic);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("XPBD: each step of dt is split into this many substeps of dt/n (\"Small Steps\")");
  ImGui::SetNextItemWidth(-110);
  changed |= ImGui::SliderInt("iterations", &def.iterations, 1, max_iterations);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("constraint projections (Gauss-Seidel sweeps) per substep");
  def.substeps = std::clamp(def.substeps, 1, 10000);
  def.iterations = std::clamp(def.iterations, 1, 1000);
  return changed;
}

bool ComplianceSlider(const char* label, double* alpha, double lo, double hi, const char* unit) {
  ImGui::PushID(label);
  // ticked: compliant (alpha > 0); unticked: rigid (alpha = 0)
  bool compliant = *alpha > 0;
  bool changed = ImGui::Checkbox("##compliant", &compliant);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("ticked: compliant (alpha > 0); unticked: rigid (alpha = 0)");
  if (changed) *alpha = compliant ? std::sqrt(lo * hi) : 0.0;
  ImGui::SameLine();
  ImGui::BeginDisabled(*alpha <= 0);
  float a = static_cast<float>(*alpha > 0 ? *alpha : lo);
  ImGui::SetNextItemWidth(-110);
  const std::string format = std::string("%.1e ") + unit;
  if (ImGui::SliderFloat(label, &a, static_cast<float>(lo), static_cast<float>(hi), *alpha > 0 ? format.c_str() : "rigid",
                         ImGuiSliderFlags_Logarithmic)) {
    *alpha = a;
    changed = true;
  }
  ImGui::EndDisabled();
  ImGui::PopID();
  return changed;
}

void ViewControls(SoftView& v, bool scale_slider) {
  ImGui::Checkbox("surface", &v.surface);
  ImGui::SameLine();
  ImGui::Checkbox("edges", &v.edges);
  ImGui::SameLine();
  ImGui::Checkbox("all", &v.all_edges);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("also shear and bend constraints");
  ImGui::Checkbox("strain colours", &v.strain);
  ImGui::SameLine();
  ImGui::Checkbox("pins", &v.pins);
  if (v.strain && scale_slider) {
    float s = static_cast<float>(100 * v.strain_scale);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("red at", &s, 0.5f, 50.0f, "%.1f %% strain", ImGuiSliderFlags_Logarithmic))
      v.strain_scale = std::max(1e-3, s / 100.0);
  }
}

void SoftReadout(const SoftBody& b) {
  const SoftProfile& p = b.profile();
  // the solve is what the step spent outside the per-step forces and the collisions
  const double solve = p.solve > 0 ? p.solve : std::max(0.0, p.total - p.forces - p.collide);
  // collisions: none without colliders; XPBD times those of its first substep only and
  // counts them once per substep (an estimate, marked ~)
  if (p.collide == 0)
    ImGui::Text("step %.3f ms (solve %.3f, no colliders)", 1e3 * p.total, 1e3 * solve);
  else
    ImGui::Text("step %.3f ms (solve %.3f, collide %s%.3f)", 1e3 * p.total, 1e3 * solve,
                b.settings().solver == SoftSolver::Xpbd ? "~" : "", 1e3 * p.collide);
  const StrainStats s = b.strain_stats();
  ImGui::Text("strain: mean %.3f %%, max %.2f %%", 100 * s.mean, 100 * s.max);
  ImGui::Text("energy: kinetic %.4f J, potential %.3f J", b.kinetic_energy(), b.potential_energy());
}

void DrawBanner(const SampleContext& ctx, const std::string& text, Color color) {
  if (!ctx.settings.show_labels || text.empty()) return;
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  // centred at the bottom of the region the panels leave free, wrapped to fit inside it
  const ScreenRect& v = ctx.view;
  const float wrap = std::max(120.0f, v.width() - 40);
  const ImVec2 ts = ImGui::CalcTextSize(text.c_str(), nullptr, false, wrap);
  const ImVec2 p(v.center_x() - 0.5f * ts.x, v.y1 - ts.y - 14);
  dl->AddRectFilled(ImVec2(p.x - 8, p.y - 4), ImVec2(p.x + ts.x + 8, p.y + ts.y + 4), IM_COL32(20, 22, 26, 200), 4);
  dl->AddText(ImGui::GetFont(), ImGui::GetFontSize(), p,
              ImGui::ColorConvertFloat4ToU32(ImVec4(color.r, color.g, color.b, 1.0f)), text.c_str(), nullptr, wrap);
}

// ---------------------------------------------------------------------------------------
// stability

// The amplification matrix of each method on x'' = -omega^2 x: explicit Euler
// [[1, h], [-w^2 h, 1]] has eigenvalues 1 +- i omega h, |.| > 1 for every h; semi-implicit
// Euler and the Verlets have det 1 and trace 2 - (omega h)^2, bounded iff |trace| < 2;
// RK4's stability polynomial 1 + z + z^2/2 + z^3/6 + z^4/24 has |.| <= 1 on the imaginary
// axis up to |z| = 2 sqrt(2); implicit Euler 1 / (1 - i omega h) is always inside. The
// library's integrator lab holds the table (and measures it: tests/lab).
double StabilityLimit(Method m) { return lab::theory_stability_limit(m); }

double MaxAngularFrequency(const SoftBody& body, int iterations) {
  return MaxAngularFrequency(body, body.settings(), iterations);
}

double MaxAngularFrequency(const SoftBody& body, const SoftBodyDef& d, int iterations) {
  const std::size_t n = body.size();
  if (n == 0) return 0;
  auto stiffness = [&](SoftConstraintKind k) {
    switch (k) {
      case SoftConstraintKind::Stretch: return d.stretch_stiffness;
      case SoftConstraintKind::Shear: return d.shear_stiffness;
      case SoftConstraintKind::Bend: return d.bend_stiffness;
    }
    return 0.0;
  };
  // the springs' unit directions and stiffnesses now
  struct Spring {
    std::uint32_t a, b;
    Vec3 n;
    double k;
  };
  std::vector<Spring> springs;
  springs.reserve(body.constraint_count());
  for (std::size_t c = 0; c < body.constraint_count(); ++c) {
    const SoftConstraint s = body.constraint(c);
    const double k = stiffness(s.kind);
    if (s.broken || !(k > 0)) continue;
    const Vec3 dd = body.position(s.b) - body.position(s.a);
    const double l = glm::length(dd);
    if (l > 0) springs.push_back({s.a, s.b, dd / l, k});
  }
  // the volume force's stiffness k_v g g^T per tet, g the gradient of its volume at its
  // four particles (g_1 = (x_2 - x_0) x (x_3 - x_0) / 6 and so on, g_0 = -g_1 - g_2 - g_3)
  struct Tet {
    std::uint32_t id[4];
    Vec3 g[4];
  };
  std::vector<Tet> tets;
  if (d.volume_stiffness > 0) {
    tets.reserve(body.tets().size());
    for (const SoftTet& t : body.tets()) {
      const Vec3 x0 = body.position(t.a);
      const Vec3 e1 = body.position(t.b) - x0, e2 = body.position(t.c) - x0, e3 = body.position(t.d) - x0;
      const Vec3 g1 = glm::cross(e2, e3) / 6.0, g2 = glm::cross(e3, e1) / 6.0, g3 = glm::cross(e1, e2) / 6.0;
      tets.push_back({{t.a, t.b, t.c, t.d}, {-(g1 + g2 + g3), g1, g2, g3}});
    }
  }
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i) w[i] = body.inverse_mass(i);
  // power iteration on A = M^-1 K from a fixed, non-symmetric start
  std::vector<Vec3> v(n), kv(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = w[i] > 0 ? Vec3(std::sin(1.0 + 0.37 * i), std::cos(2.0 + 0.71 * i), std::sin(0.5 + 1.13 * i)) : Vec3(0);
  double lambda = 0;
  for (int it = 0; it < iterations; ++it) {
    std::fill(kv.begin(), kv.end(), Vec3(0));
    for (const Spring& s : springs) {
      const Vec3 f = s.k * glm::dot(v[s.b] - v[s.a], s.n) * s.n;
      kv[s.b] += f;
      kv[s.a] -= f;
    }
    for (const Tet& t : tets) {
      double dv = 0;
      for (int k = 0; k < 4; ++k) dv += glm::dot(t.g[k], v[t.id[k]]);
      for (int k = 0; k < 4; ++k) kv[t.id[k]] += d.volume_stiffness * dv * t.g[k];
    }
    // the Rayleigh quotient in the mass inner product: v^T K v / v^T M v
    double num = 0, den = 0, norm = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!(w[i] > 0)) continue;
      num += glm::dot(v[i], kv[i]);
      den += glm::dot(v[i], v[i]) / w[i];
    }
    if (!(den > 0)) return 0;
    lambda = num / den;
    for (std::size_t i = 0; i < n; ++i) {
      v[i] = w[i] * kv[i];
      norm = std::max(norm, glm::length(v[i]));
    }
    if (!(norm > 0)) return 0;
    for (Vec3& x : v) x /= norm;
  }
  return std::sqrt(std::max(lambda, 0.0));
}

}  // namespace pba::app
