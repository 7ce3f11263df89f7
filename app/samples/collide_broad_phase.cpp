// "Collision/Broad phase" (workbook chapter 5; issue 10 section 3): thousands of boxes
// flying about in a closed container (pba::MovingBoxes, the scene the tests and benchmark
// use), their overlapping pairs found every step by the method chosen in the panel: the
// dynamic AABB tree, the uniform grid, sweep and prune or brute force. Every method gives
// the same pairs; the panel shows the pair count and the milliseconds each method takes,
// and the tree's nodes (or the grid's occupied cells) are drawn.
//
//   --option method=tree|grid|sap|brute-force  --option count=N (100..20000)
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "offset_draw.h"
#include "particles_common.h"
#include "pba/collide/broad_phase.h"
#include "pba/collide/moving_boxes.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

constexpr Color kFree = colors::blue;
constexpr Color kTouching = colors::orange;
constexpr BroadPhaseMethod kMethods[] = {BroadPhaseMethod::Tree, BroadPhaseMethod::Grid,
                                         BroadPhaseMethod::SweepAndPrune, BroadPhaseMethod::BruteForce};
constexpr const char* kMethodNames[] = {"dynamic tree", "uniform grid", "sweep and prune", "brute force"};

// a colour per method for the timing plot
constexpr Color kMethodColor[] = {colors::green, colors::cyan, colors::purple, colors::red};

class BroadPhaseLab final : public Sample {
 public:
  explicit BroadPhaseLab(SampleContext& ctx) : Sample(ctx) {
    count_ = OptionInteger(ctx, "count", 2000, 100, 20000);
    const BroadPhaseMethod m = broad_phase_method_from_string(ctx.option("method", "tree"), "--option method");
    method_ = static_cast<int>(std::find(std::begin(kMethods), std::end(kMethods), m) - std::begin(kMethods));
    flags_.tree = true;
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<BroadPhaseLab>(ctx); }

  void Step(double, double dt) override {
    // move the boxes, hand the broad phase their new bounds, find the pairs
    scene_.step(dt);
    for (std::size_t i = 0; i < scene_.size(); ++i) bp_.move_proxy(ids_[i], scene_.box(i));
    bp_.set_method(kMethods[method_]);
    bp_.update_pairs();
    // mark the boxes in a pair
    std::fill(touching_.begin(), touching_.end(), 0);
    for (const ProxyPair& p : bp_.pairs()) {
      touching_[bp_.user_data(p.a)] = 1;
      touching_[bp_.user_data(p.b)] = 1;
    }
    // the history for the panel
    const BroadPhaseStats& st = bp_.stats();
    ms_[method_] = 0.9 * ms_[method_] + 0.1 * st.seconds * 1e3;
    if (hist_t_.size() >= 600) {
      hist_t_.erase(hist_t_.begin());
      hist_ms_.erase(hist_ms_.begin());
      hist_pairs_.erase(hist_pairs_.begin());
    }
    time_ += dt;
    hist_t_.push_back(static_cast<float>(time_));
    hist_ms_.push_back(static_cast<float>(st.seconds * 1e3));
    hist_pairs_.push_back(static_cast<float>(st.pairs));
  }

  void Draw(Renderer& r, double) override {
    // the container, centred on the origin above the ground
    const Vec3 o = offset();
    const double s = scene_.side();
    draw_box_edges(r, {o, o + Vec3(s)}, colors::grey);
    // the boxes, orange when in a pair
    const auto c = scene_.centers();
    const auto h = scene_.half_extents();
    for (std::size_t i = 0; i < scene_.size(); ++i)
      r.box(c[i] + o, h[i], Quat(1, 0, 0, 0), touching_[i] ? kTouching : kFree);
    // the tree or grid, shifted like the boxes
    if (flags_.tree || flags_.aabbs) {
      OffsetDraw shifted(r, o);
      draw_broad_phase(bp_, shifted, flags_, depth_);
    }
  }

  void DrawUI() override {
    ImGui::TextWrapped("%s boxes bouncing in a %.0f m box; orange ones overlap another. Every method finds the "
                       "same pairs, sorted by proxy id.",
                       Thousands(count_).c_str(), scene_.side());
    for (int k = 0; k < 4; ++k) {
      ImGui::RadioButton(kMethodNames[k], &method_, k);
      if (k % 2 == 0) ImGui::SameLine(150);
    }
    const BroadPhaseStats& st = bp_.stats();
    ImGui::Text("pairs: %s   box tests: %s", Thousands(static_cast<long long>(st.pairs)).c_str(),
                Thousands(static_cast<long long>(st.box_tests)).c_str());
    ImGui::Text("this step: %.3f ms (%s)", st.seconds * 1e3, kMethodNames[method_]);
    for (int k = 0; k < 4; ++k)
      if (ms_[k] > 0)
        ImGui::TextColored(ImVec4(kMethodColor[k].r, kMethodColor[k].g, kMethodColor[k].b, 1), "  %-16s %8.3f ms",
                           kMethodNames[k], ms_[k]);
    if (st.method == BroadPhaseMethod::Tree)
      ImGui::Text("tree: height %d, inner area / root area %.1f, %s queried", st.tree_height, st.tree_area_ratio,
                  Thousands(static_cast<long long>(st.reinserted)).c_str());
    if (st.method == BroadPhaseMethod::Grid) ImGui::Text("grid cell: %.2f m", st.grid_cell);

    std::vector<PlotSeries> series{
        Series(hist_t_.data(), hist_ms_.data(), static_cast<int>(hist_t_.size()), kMethodColor[method_], 1.5f)};
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "ms per step";
    ax.y_lo = 0;
    LinePlot("ms", series, ax, 110);

    ImGui::Checkbox("draw tree / grid", &flags_.tree);
    ImGui::SameLine();
    ImGui::Checkbox("draw boxes' AABBs", &flags_.aabbs);
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("tree depth", &depth_, 1, 20);
    int n = count_;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderInt("boxes", &n, 100, 20000, "%d", ImGuiSliderFlags_Logarithmic)) {
      count_ = n;
      build();
    }
    float fast = static_cast<float>(fast_);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("fast share", &fast, 0.0f, 1.0f, "%.2f")) {
      fast_ = fast;
      build();
    }
  }

  std::vector<Color> ExpectedColors() const override { return {kFree, kTouching}; }

 private:
  Vec3 offset() const { return {-0.5 * scene_.side(), 0.0, -0.5 * scene_.side()}; }

  void build() {
    scene_ = MovingBoxes({.count = count_, .speed = 2.0, .fast_fraction = fast_, .fast_speed = 8.0, .seed = 1});
    bp_ = BroadPhase({.method = kMethods[method_]});
    bp_.reserve(scene_.size());
    ids_.clear();
    for (std::size_t i = 0; i < scene_.size(); ++i) ids_.push_back(bp_.create_proxy(scene_.box(i), {}, i));
    bp_.update_pairs();
    touching_.assign(scene_.size(), 0);
    hist_t_.clear(), hist_ms_.clear(), hist_pairs_.clear();
    const float side = static_cast<float>(scene_.side());
    ctx_.camera->frame({0.0f, 0.5f * side, 0.0f}, 0.9f * side, 0.5f, 0.35f);
  }

  int count_ = 2000;
  int method_ = 0;
  int depth_ = 7;
  double fast_ = 0.1;
  double time_ = 0;
  DrawFlags flags_;
  MovingBoxes scene_{MovingBoxesDef{}};
  BroadPhase bp_;
  std::vector<ProxyId> ids_;
  std::vector<std::uint8_t> touching_;
  double ms_[4] = {0, 0, 0, 0};
  std::vector<float> hist_t_, hist_ms_, hist_pairs_;
};

static int reg = RegisterSample("Collision", "Broad phase", BroadPhaseLab::Create);

}  // namespace
}  // namespace pba::app
