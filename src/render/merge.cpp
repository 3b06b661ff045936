// Moment-matched merging of flat, single-coloured groups of Gaussians that share a source-view cell.
#include "render/merge.h"

#include <torch/torch.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/config.h"
#include "core/error.h"

namespace isplat {

void MergeOptions::visit(ConfigVisitor& v) {
  v.field("cell_px", cell_px,
          "merge the Gaussians whose means project into one cell of this many source pixels into one Gaussian "
          "with their mean and covariance, when they are flat and of one colour (0 = off)",
          Range::at_least(0.0));
  v.field("max_color", max_color,
          "merge a cell only when every member's colour (as stored) is within this of the cell's mean (any channel)",
          Range::unit());
  v.field("max_flatness", max_flatness,
          "merge a cell only when the merged Gaussian's thickness is at most this fraction of its narrower in-plane "
          "width, so a cell across a depth edge stays apart",
          Range::unit());
  v.field("min_normal_cos", min_normal_cos,
          "merge a cell only when every flat member's normal is within this cosine of the merged Gaussian's normal",
          Range::unit());
  v.field("split", split,
          "a cell that cannot merge whole is split by colour: around its heaviest remaining member, the members "
          "within max_color of it (then of their weighted mean) try to merge on their own, so one odd pixel no longer "
          "keeps its whole cell apart");
}

namespace {

// Cells further than this from the image (in cells) are not grouped: their keys would overflow.
constexpr int64_t kMaxCell = int64_t{1} << 20;

Eigen::Matrix3d rotation_of(const double* q) {
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  const double norm = quat.norm();
  return norm > 0 && std::isfinite(norm) ? Eigen::Matrix3d(quat.normalized().toRotationMatrix())
                                         : Eigen::Matrix3d::Identity();
}

enum class Outcome { merged, invalid, color, shape, normal };

// One pass over cells of `o.cell_px` source pixels; adds its counts to `r`.
Gaussians merge_pass(const Gaussians& g, const Camera& source, const MergeOptions& o, MergeCounts& r) {
  const double cell_px = o.cell_px;
  const int64_t n = g.count();
  const auto dtype = g.means.scalar_type();
  auto f64 = [&](const torch::Tensor& t, int64_t cols) {
    ISPLAT_CHECK(t.defined() && t.numel() == n * cols, "merge_gaussians: a Gaussian tensor ",
                 t.defined() ? t.sizes() : c10::IntArrayRef{}, " does not match ", n, " means");
    return t.detach().to(torch::kFloat64).reshape({n, cols}).contiguous();
  };
  const torch::Tensor means_t = f64(g.means, 3), scales_t = f64(g.scales, 3), quats_t = f64(g.quats, 4),
                      colors_t = f64(g.colors, 3), opac_t = f64(g.opacities, 1);
  const double *means = means_t.data_ptr<double>(), *scales = scales_t.data_ptr<double>(),
               *quats = quats_t.data_ptr<double>(), *colors = colors_t.data_ptr<double>(),
               *opac = opac_t.data_ptr<double>();
  const torch::Tensor K = source.K.to(torch::kFloat64).contiguous(), T = source.T_cw.to(torch::kFloat64).contiguous();
  const auto k = K.accessor<double, 2>();
  const auto t = T.accessor<double, 2>();

  // (cell key, index); Gaussians that are not grouped get a key of their own below every cell key.
  std::vector<std::pair<int64_t, int64_t>> keyed(n);
  for (int64_t i = 0; i < n; ++i) {
    const double* m = means + 3 * i;
    double c[3];
    for (int a = 0; a < 3; ++a) c[a] = t[a][0] * m[0] + t[a][1] * m[1] + t[a][2] * m[2] + t[a][3];
    keyed[i] = {-1 - i, i};
    if (!(c[2] > 0)) continue;
    const double u = (k[0][0] * c[0] + k[0][1] * c[1]) / c[2] + k[0][2], v = k[1][1] * c[1] / c[2] + k[1][2];
    const double cu = std::floor(u / cell_px), cv = std::floor(v / cell_px);
    if (!(std::abs(cu) < kMaxCell && std::abs(cv) < kMaxCell)) continue;
    const int64_t key = (static_cast<int64_t>(cv) + kMaxCell) * (2 * kMaxCell) + (static_cast<int64_t>(cu) + kMaxCell);
    keyed[i] = {key, i};
  }
  std::sort(keyed.begin(), keyed.end());

  std::vector<double> out_means, out_scales, out_quats, out_colors, out_opac;
  for (auto* v : {&out_means, &out_scales, &out_colors}) v->reserve(3 * n);
  out_quats.reserve(4 * n);
  out_opac.reserve(n);
  auto copy = [&](int64_t i) {
    out_means.insert(out_means.end(), means + 3 * i, means + 3 * i + 3);
    out_scales.insert(out_scales.end(), scales + 3 * i, scales + 3 * i + 3);
    out_quats.insert(out_quats.end(), quats + 4 * i, quats + 4 * i + 4);
    out_colors.insert(out_colors.end(), colors + 3 * i, colors + 3 * i + 3);
    out_opac.push_back(opac[i]);
  };
  auto color_of = [&](int64_t i) { return Eigen::Vector3d(colors[3 * i], colors[3 * i + 1], colors[3 * i + 2]); };
  // A member's local axes by size (ties in axis order) and its weight: opacity x footprint area (the two larger).
  auto axes_by_size = [&](int64_t i, int axes[3]) {
    const double* s = scales + 3 * i;
    axes[0] = 0, axes[1] = 1, axes[2] = 2;
    std::stable_sort(axes, axes + 3, [&](int x, int y) { return std::abs(s[x]) < std::abs(s[y]); });
    return opac[i] * std::abs(s[axes[1]]) * std::abs(s[axes[2]]);
  };
  auto weight_of = [&](int64_t i) {
    int axes[3];
    return axes_by_size(i, axes);
  };
  // What a group needs of each member, read once.
  struct Member {
    Eigen::Vector3d mean;
    Eigen::Matrix3d rotation;
    double weight;
    int normal_axis;  // the local axis of a flat member's normal; -1 when it is not flat (no normal to compare)
  };
  std::vector<Member> group;
  // Tries one group; on success appends the merged Gaussian.
  auto merge = [&](const std::vector<int64_t>& members) {
    group.clear();
    double weight_sum = 0, opacity = 0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero(), color = Eigen::Vector3d::Zero();
    for (const int64_t i : members) {
      int axes[3];
      const double w = axes_by_size(i, axes);
      if (!(w > 0) || !std::isfinite(w)) return Outcome::invalid;
      const bool flat = std::abs(scales[3 * i + axes[0]]) <= 0.5 * std::abs(scales[3 * i + axes[1]]);
      group.push_back({Eigen::Vector3d(means[3 * i], means[3 * i + 1], means[3 * i + 2]), rotation_of(quats + 4 * i), w,
                       flat ? axes[0] : -1});
      weight_sum += w;
      mean += w * group.back().mean;
      color += w * color_of(i);
      opacity += w * opac[i];
    }
    mean /= weight_sum, color /= weight_sum, opacity /= weight_sum;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t j = 0; j < members.size(); ++j) {
      const int64_t i = members[j];
      if ((color_of(i) - color).cwiseAbs().maxCoeff() > o.max_color) return Outcome::color;
      const Member& m = group[j];
      const Eigen::Vector3d s2(scales[3 * i] * scales[3 * i], scales[3 * i + 1] * scales[3 * i + 1],
                               scales[3 * i + 2] * scales[3 * i + 2]);
      const Eigen::Vector3d d = m.mean - mean;
      cov += m.weight * (m.rotation * s2.asDiagonal() * m.rotation.transpose() + d * d.transpose());
    }
    cov /= weight_sum;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    if (eig.info() != Eigen::Success) return Outcome::invalid;
    Eigen::Vector3d lambda = eig.eigenvalues().cwiseMax(0.0);  // ascending
    if (!(lambda[1] > 0) || std::sqrt(lambda[0] / lambda[1]) > o.max_flatness) return Outcome::shape;
    Eigen::Matrix3d axes = eig.eigenvectors();
    // Flat members must lie in the merged plane: two Gaussians a depth step apart make a thin line, which the
    // flatness test alone would pass.
    for (const Member& m : group)
      if (m.normal_axis >= 0 && std::abs(m.rotation.col(m.normal_axis).dot(axes.col(0))) < o.min_normal_cos)
        return Outcome::normal;
    // Members that tile a patch cover more than their moment-matched Gaussian does (it has one peak where the
    // patch is flat-topped), so the merged Gaussian's in-plane axes grow until its footprint (opacity x area)
    // equals the members' total: a plain wall stays closed instead of showing gaps between merged cells.
    const double area_ratio = weight_sum / opacity / std::sqrt(lambda[1] * lambda[2]);
    if (area_ratio > 1) lambda[1] *= area_ratio, lambda[2] *= area_ratio;
    if (axes.determinant() < 0) axes.col(0) = -axes.col(0);
    const Eigen::Quaterniond q(axes);
    out_means.insert(out_means.end(), {mean[0], mean[1], mean[2]});
    out_scales.insert(out_scales.end(), {std::sqrt(lambda[0]), std::sqrt(lambda[1]), std::sqrt(lambda[2])});
    out_quats.insert(out_quats.end(), {q.w(), q.x(), q.y(), q.z()});
    out_colors.insert(out_colors.end(), {color[0], color[1], color[2]});
    out_opac.push_back(opacity);
    r.groups += 1;
    r.members += static_cast<int64_t>(members.size());
    return Outcome::merged;
  };
  auto count_refusal = [&](Outcome outcome) {
    r.refused_color += outcome == Outcome::color;
    r.refused_shape += outcome == Outcome::shape;
    r.refused_normal += outcome == Outcome::normal;
  };
  // The members within max_color of `centre` (any channel).
  auto near_color = [&](const std::vector<int64_t>& from, const Eigen::Vector3d& centre) {
    std::vector<int64_t> near;
    for (const int64_t i : from)
      if ((color_of(i) - centre).cwiseAbs().maxCoeff() <= o.max_color) near.push_back(i);
    return near;
  };
  // Splits a cell refused whole: around its heaviest remaining member, the members within max_color of it, then
  // of their weighted mean, try to merge on their own; what does not merge is kept as it is. A cell whose first
  // part is the whole cell stays apart (it was tried whole already).
  auto merge_split = [&](std::vector<int64_t> rest) {
    const size_t whole = rest.size();
    while (rest.size() > 1) {
      const int64_t seed = *std::max_element(rest.begin(), rest.end(),
                                             [&](int64_t a, int64_t b) { return weight_of(a) < weight_of(b); });
      std::vector<int64_t> part = near_color(rest, color_of(seed));
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      double w = 0;
      for (const int64_t i : part) centre += weight_of(i) * color_of(i), w += weight_of(i);
      if (w > 0) part = near_color(rest, centre / w);
      if (std::find(part.begin(), part.end(), seed) == part.end()) part.push_back(seed);
      if (part.size() == whole) break;
      const Outcome outcome = part.size() > 1 ? merge(part) : Outcome::invalid;
      if (outcome != Outcome::merged) {
        count_refusal(outcome);
        for (const int64_t i : part) copy(i);
      }
      rest.erase(std::remove_if(rest.begin(), rest.end(),
                                [&](int64_t i) { return std::find(part.begin(), part.end(), i) != part.end(); }),
                 rest.end());
    }
    for (const int64_t i : rest) copy(i);
  };
  std::vector<int64_t> cell;
  for (int64_t begin = 0; begin < n;) {
    int64_t end = begin + 1;
    if (keyed[begin].first >= 0)
      while (end < n && keyed[end].first == keyed[begin].first) ++end;
    cell.clear();
    for (int64_t j = begin; j < end; ++j) cell.push_back(keyed[j].second);
    if (cell.size() == 1) r.alone += 1;
    const Outcome outcome = cell.size() > 1 ? merge(cell) : Outcome::invalid;
    if (outcome != Outcome::merged) {
      count_refusal(outcome);
      if (o.split && cell.size() > 2) {
        merge_split(cell);
      } else {
        for (const int64_t i : cell) copy(i);
      }
    }
    begin = end;
  }

  const int64_t m = static_cast<int64_t>(out_opac.size());
  auto tensor = [&](std::vector<double>& v, std::vector<int64_t> shape) {
    return torch::from_blob(v.data(), shape, torch::kFloat64).clone().to(dtype);
  };
  Gaussians merged;
  merged.means = tensor(out_means, {m, 3});
  merged.scales = tensor(out_scales, {m, 3});
  merged.quats = tensor(out_quats, {m, 4});
  merged.colors = tensor(out_colors, {m, 3});
  merged.opacities = g.opacities.dim() == 2 ? tensor(out_opac, {m, 1}) : tensor(out_opac, {m});
  return merged;
}

}  // namespace

MergeResult merge_gaussians(const Gaussians& g, const Camera& source, const MergeOptions& o) {
  ISPLAT_CHECK(!g.batched() && source.batch() == 0, "merge_gaussians: takes one unbatched set and camera");
  torch::NoGradGuard no_grad;
  MergeResult r;
  r.before = g.count();
  r.merged = g;
  if (o.cell_px <= 0) return r;
  if (r.merged.count() >= 2) r.merged = merge_pass(r.merged, source, o, r);
  return r;
}

}  // namespace isplat
