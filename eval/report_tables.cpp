// The report's tables and files: report.md, report.csv, report.json, differences.csv, slopes.csv, breakdown.csv,
// by_region.csv.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include "core/build_info.h"
#include "core/error.h"
#include "eval/report.h"
#include "eval/report_parts.h"
#include "io/atomic_file.h"
#include "io/chart.h"
#include "io/table.h"

namespace isplat {
namespace fs = std::filesystem;
using reporting::perturbation_strength;
using reporting::sweep_families;
using reporting::sweep_points;

namespace reporting {
void add_method_columns(Table& t) {
  t.columns.insert(t.columns.end(), {{"method"}, {"sweep_key"}, {"budget"}, {"sweep_value", -1}});
}

void add_method_cells(std::vector<TableCell>& cells, const MethodId& m) {
  auto text = [](const std::string& s) { return s.empty() ? TableCell() : TableCell(s); };
  cells.insert(cells.end(), {m.name, text(m.sweep.key), text(m.sweep.budget),
                             m.sweep.any() ? TableCell(m.sweep.value) : TableCell()});
}
}  // namespace reporting

using reporting::add_method_cells;
using reporting::add_method_columns;

namespace {
constexpr const char* kStages[] = {"prior", "sampler", "encoder", "decoder", "composer", "prune"};

std::vector<std::string> datasets_of(const std::vector<ReportRow>& rows) {
  std::vector<std::string> datasets;
  for (const auto& r : rows)
    if (std::find(datasets.begin(), datasets.end(), r.dataset) == datasets.end()) datasets.push_back(r.dataset);
  return datasets;
}

// "0.12 [0.05, 0.20]", with "(no difference)" when the interval contains 0; "n/a" without pairs.
std::string interval_text(const Interval& i, int digits) {
  return i.n == 0 ? std::string("n/a")
                  : cat(format_fixed(i.mean, digits), " [", format_fixed(i.lo, digits), ", ",
                        format_fixed(i.hi, digits), "]", i.excludes_zero() ? "" : " (no difference)");
}

// The scores of dataset d: one row per method and bin.
Table scores_table(const std::vector<ReportRow>& rows, const std::string& d, const std::vector<std::string>& nets) {
  Table t;
  t.columns = {{"method"}, {"bin"}, {"pairs"}, {"psnr", 2, "PSNR"}, {"ssim", 4, "SSIM"}};
  for (const auto& n : nets) t.columns.push_back({"lpips_" + n, 4, "LPIPS (" + n + ")"});
  for (const TableColumn& c : std::initializer_list<TableColumn>{
           {"infer_ms", 0, "infer ms"}, {"render_ms", 0, "render ms"}, {"gaussians", 0, "Gaussians"}})
    t.columns.push_back(c);
  for (const auto& r : rows) {
    if (r.dataset != d) continue;
    std::vector<TableCell> cells = {
        r.method.label(), r.bin,
        r.pairs < r.requested ? TableCell(cat(r.pairs, " of ", r.requested)) : TableCell(r.pairs), r.psnr, r.ssim};
    for (const auto& n : nets) cells.push_back(r.lpips.at(n));
    cells.insert(cells.end(), {r.infer_ms, r.render_ms, r.gaussians});
    t.add(std::move(cells));
  }
  return t;
}

// Where the time goes on dataset d: the stages, the render and the memory, all bins.
Table time_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"Gaussians"}};
  for (const char* st : kStages) t.columns.push_back({st, 1});
  for (const TableColumn& c :
       std::initializer_list<TableColumn>{{"infer", 0}, {"render", 1}, {"peak MB", 0}, {"work MB", 1}})
    t.columns.push_back(c);
  for (const auto& r : rows) {
    if (r.dataset != d || r.bin != "all") continue;
    const bool pruned = std::isfinite(r.decoded) && std::llround(r.decoded) != std::llround(r.gaussians);
    std::vector<TableCell> cells = {r.method.label(),
                                    format_fixed(r.decoded, 0) + (pruned ? " -> " + format_fixed(r.gaussians, 0) : "")};
    for (const char* st : kStages) cells.push_back(r.stage_ms.count(st) ? TableCell(r.stage_ms.at(st)) : TableCell());
    cells.insert(cells.end(), {r.infer_ms, r.render_ms, r.peak_mb, r.work_mb});
    t.add(std::move(cells));
  }
  return t;
}

// What pruning removed, as mean Gaussians per pair (render/prune_counts), for the methods that prune.
Table pruning_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"decoded"}, {"low opacity"}, {"low contribution"}, {"merged away"}, {"rendered"}};
  for (const auto& r : rows) {
    if (r.dataset != d || r.bin != "all" || r.prune_counts.empty()) continue;
    auto count = [&](const char* k) { return r.prune_counts.count(k) ? r.prune_counts.at(k) : 0.0; };
    t.add({r.method.label(), r.decoded, count("low_opacity"), count("low_contribution"),
           count("merged_members") - count("merged_groups"), r.gaussians});
  }
  return t;
}

// Holes, cracks and normals on dataset d, for the methods that render.
Table stability_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"bin"}, {"holes %", 2}, {"cracks %", 2}, {"normals deg", 2}};
  for (const auto& r : rows)
    if (r.dataset == d && std::isfinite(r.hole_rate))
      t.add({r.method.label(), r.bin, 100 * r.hole_rate, 100 * r.crack_rate, r.normal_deg});
  return t;
}

// PSNR and holes at the working size and at each display factor (scoring.display_factors), for the methods scored
// there on dataset d.
Table display_table(const std::vector<ReportRow>& rows, const std::string& d) {
  std::set<double> factors;
  for (const auto& r : rows)
    if (r.dataset == d)
      for (const auto& [factor, score] : r.display) factors.insert(factor);
  Table t;
  if (factors.empty()) return t;
  t.columns = {{"method"}, {"bin"}, {"psnr", 2, "PSNR"}, {"hole_rate", 2, "holes %"}};
  for (double f : factors) {
    const std::string x = format_fixed(f, f == std::floor(f) ? 0 : 1);
    t.columns.push_back({"psnr_x" + x, 2, "PSNR at " + x + "x"});
    t.columns.push_back({"hole_rate_x" + x, 2, "holes % at " + x + "x"});
  }
  for (const auto& r : rows) {
    if (r.dataset != d || r.display.empty()) continue;
    std::vector<TableCell> cells = {r.method.label(), r.bin, r.psnr, 100 * r.hole_rate};
    for (double f : factors) {
      const auto it = r.display.find(f);
      const double nan = std::numeric_limits<double>::quiet_NaN();
      cells.push_back(it == r.display.end() ? nan : it->second.psnr);
      cells.push_back(it == r.display.end() ? nan : 100 * it->second.hole_rate);
    }
    t.add(std::move(cells));
  }
  return t;
}

// scoring.align_scale on dataset d: each method's factors over the aligned pairs (geometric mean and spread).
Table scale_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"}, {"bin"}, {"aligned"}, {"no sample"}, {"scale", 4}, {"spread", 4}};
  for (const auto& r : rows)
    if (r.dataset == d && (r.scale_pairs > 0 || r.scale_missed > 0))
      t.add({r.method.label(), r.bin, r.scale_pairs, r.scale_missed, r.scale, r.scale_spread});
  return t;
}

// Sparse-prior methods on dataset d: the densified depth against the true depth beside PSNR.
Table densify_table(const std::vector<ReportRow>& rows, const std::string& d) {
  Table t;
  t.columns = {{"method"},
               {"bin"},
               {"psnr", 2, "PSNR"},
               {"AbsRel unprompted", 4},
               {"d<1.25 unprompted", 4},
               {"pairs"},
               {"AbsRel removed", 4},
               {"d<1.25 removed", 4},
               {"pairs removed"}};
  for (const auto& r : rows)
    if (r.dataset == d && (r.unprompted.pixels > 0 || r.removed.pixels > 0))
      t.add({r.method.label(), r.bin, r.psnr, r.unprompted.abs_rel, r.unprompted.delta1, r.unprompted.pixels,
             r.removed.abs_rel, r.removed.delta1, r.removed.pixels});
  return t;
}

// The paper's figure for a sweep, where it reports one: Table 4's LiDAR prompt noise (override:prior.sparse.noise,
// family key "noise"), 25.9 -> 23.6 dB on ETH3D from 0% to 5%.
std::string paper_slope(const std::string& key) {
  return key == "noise" ? "-0.46 dB per % (Table 4: ETH3D, 25.9 -> 23.6 dB from 0 to 5%)" : "-";
}

// Per swept family: PSNR against the swept value, its least-squares slope (per 1% for shares and noise
// sigmas) and whether PSNR is monotone in the value (graceful degradation falls steadily with noise). The
// unperturbed run counts as the neutral value (see sweep_points).
Table sweep_table(const std::vector<ReportRow>& rows, const std::string& d, const std::vector<SweepSlope>& intervals) {
  Table t;
  t.columns = {
      {"sweep"},    {"values"}, {"PSNR"}, {"slope"}, {"slope 95% interval (pairs)"}, {"PSNR as strength grows"},
      {"the paper"}};
  std::vector<MethodId> families = sweep_families(rows, d);
  std::sort(families.begin(), families.end(), [](auto& a, auto& b) { return a.family() < b.family(); });
  for (const auto& family : families) {
    auto pts = sweep_points(rows, d, family, &ReportRow::psnr);
    pts.erase(std::remove_if(pts.begin(), pts.end(), [](auto& p) { return !std::isfinite(p.second); }), pts.end());
    if (pts.size() < 2) continue;
    const std::string key = family.sweep.axis();
    const auto [strength, unit] = perturbation_strength(key);
    std::vector<std::pair<double, double>> by_strength;
    for (const auto& [x, y] : pts) by_strength.push_back({strength(x), y});
    std::sort(by_strength.begin(), by_strength.end());
    double mx = 0, my = 0;
    for (const auto& [x, y] : by_strength) mx += x, my += y;
    mx /= static_cast<double>(pts.size()), my /= static_cast<double>(pts.size());
    double sxy = 0, sxx = 0;
    bool falls = true, rises = true;
    for (const auto& [x, y] : by_strength) sxy += (x - mx) * (y - my), sxx += (x - mx) * (x - mx);
    for (size_t k = 1; k < by_strength.size(); ++k)
      falls = falls && by_strength[k].second <= by_strength[k - 1].second,
      rises = rises && by_strength[k].second >= by_strength[k - 1].second;
    const double slope = sxx > 0 ? sxy / sxx : std::numeric_limits<double>::quiet_NaN();
    std::string xs, ys;
    for (const auto& [x, y] : pts) {
      std::ostringstream v;
      v << std::setprecision(4) << x;
      xs += (xs.empty() ? "" : ", ") + v.str(), ys += (ys.empty() ? "" : ", ") + format_fixed(y, 2);
    }
    const auto ci = std::find_if(intervals.begin(), intervals.end(),
                                 [&](const SweepSlope& s) { return s.dataset == d && s.family == family.family(); });
    const std::string interval =
        ci == intervals.end() || ci->slope.n == 0
            ? std::string("n/a")
            : cat("[", format_fixed(ci->slope.lo, 3), ", ", format_fixed(ci->slope.hi, 3), "] (", ci->slope.n, "): ",
                  ci->slope.hi < 0   ? "falls"
                  : ci->slope.lo > 0 ? "rises"
                                     : "no measurable change");
    t.add({family.family(), xs, ys, format_fixed(slope, 3) + " dB per " + unit, interval,
           falls   ? "falls"
           : rises ? "rises"
                   : "not monotone",
           paper_slope(key)});
  }
  return t;
}

// Finer baseline groups and motion types (see breakdown()): Markdown (`digits` 2/3) or CSV and JSON (4/5).
Table breakdown_table(const std::vector<ReportRow>& breakdowns, const std::string& d,
                      const std::vector<std::string>& nets, bool markdown) {
  Table t;
  const int p = markdown ? 2 : 4, s = markdown ? 3 : 5;
  if (markdown) {
    t.columns.push_back({"method"});
  } else {
    t.columns.push_back({"dataset"});
    add_method_columns(t);
  }
  t.columns.insert(t.columns.end(), {{"group"}, {"pairs"}, {"psnr", p, "PSNR"}, {"ssim", s, "SSIM"}});
  for (size_t k = 0; k < nets.size() && (k == 0 || !markdown); ++k)
    t.columns.push_back({"lpips_" + nets[k], s, "LPIPS"});
  if (markdown) {
    t.columns.insert(t.columns.end(), {{"hole_rate", 2, "holes %"}, {"crack_rate", 2, "cracks %"}});
  } else {
    t.columns.insert(t.columns.end(), {{"hole_rate", 5}, {"crack_rate", 5}, {"normal_deg", 3}});
  }
  const double pct = markdown ? 100 : 1;
  for (const auto& r : breakdowns) {
    if (!d.empty() && r.dataset != d) continue;
    std::vector<TableCell> cells;
    if (markdown) {
      cells.push_back(r.method.label());
    } else {
      cells.push_back(r.dataset);
      add_method_cells(cells, r.method);
    }
    cells.insert(cells.end(), {r.bin, r.pairs, r.psnr, r.ssim});
    for (size_t k = 0; k < nets.size() && (k == 0 || !markdown); ++k) cells.push_back(r.lpips.at(nets[k]));
    cells.insert(cells.end(), {pct * r.hole_rate, pct * r.crack_rate});
    if (!markdown) cells.push_back(r.normal_deg);
    t.add(std::move(cells));
  }
  return t;
}

// One dataset's section of report.md: scores, time, pruning, stability, sweeps and the finer breakdown.
std::string dataset_section(const std::vector<ReportRow>& rows, const std::string& d,
                            const std::vector<std::string>& nets, const std::vector<SweepSlope>& slopes,
                            const std::vector<ReportRow>& breakdowns) {
  std::string md = "## " + d + "\n\n" + table_markdown(scores_table(rows, d, nets));
  // A captioned table; the optional ones only when they have rows.
  const auto section = [&md](const std::string& caption, const Table& table, bool always = false) {
    if (always || !table.rows.empty()) md += "\n" + caption + ":\n\n" + table_markdown(table);
  };
  section(
      "Where the time goes (ms per pair, all bins; Gaussians decoded -> rendered after pruning; peak = the process's "
      "resident peak during one prediction and render, which keeps what earlier pairs and methods left resident; work "
      "= the CPU tensor memory one prediction and render needed beyond what was live before, largest over pairs, "
      "which is what a budget changes)",
      time_table(rows, d), true);
  section(
      "Pruning (mean Gaussians per pair, all bins): decoded, removed below the opacity floor, removed as faint "
      "over the source and nearby views (largest alpha*T below the threshold), merged away into neighbours, "
      "rendered",
      pruning_table(rows, d));
  section(
      "Stability: holes = masked pixels with rendered alpha < 0.5; cracks = neighbour pairs whose rendered depth "
      "jumps by > 5% where the reference depth is smooth; normals = mean angle (degrees) between neighbouring "
      "rendered normals on reference-planar surfaces",
      stability_table(rows, d), true);
  section(
      "At display resolution: each target rendered again at k times its size, scored against the target image "
      "and mask resized to match (bilinear): what a viewer above the working size sees, gaps between Gaussians "
      "included",
      display_table(rows, d));
  section(
      "Scale alignment (scoring.align_scale): each prediction scaled about the source camera by the median ratio "
      "of reference to rendered depth at the source view's samples; the geometric mean of the factors and their "
      "spread (exp of the standard deviation of their logs; 1 = the same factor on every pair); pairs without a "
      "usable sample kept factor 1",
      scale_table(rows, d));
  section(
      "Densification (sparse-prior methods): the densified depth against the true source depth, AbsRel and the "
      "share within 1.25x, on the pixels that held no prompt and on the pixels whose depth the perturbation "
      "removed (means over the pairs measured)",
      densify_table(rows, d));
  section(
      "Sweeps: PSNR (all bins) against the perturbation's strength (noise and shares in %, scale and exposure as "
      "abs(ln value) so both sides count, JPEG as quality lost, prompts as e-folds fewer), its least-squares slope "
      "with its 95% interval over pairs (the mean of per-pair slopes on the pairs every point scored; an interval "
      "containing 0 is no measurable change), and whether the mean PSNR falls steadily as the strength grows "
      "(graceful)",
      sweep_table(rows, d, slopes));
  section(
      "By baseline (finer than the protocol's bins) and by motion type (what moves the image most: lateral or "
      "forward translation, or rotation)",
      breakdown_table(breakdowns, d, nets, true));
  return md + "\n";
}

// Every method against the reference: over all pairs (bin "all") or per bin, for report.md.
Table differences_markdown(const std::vector<DiffRow>& differences, bool per_bin) {
  Table t;
  if (per_bin) {
    t.columns = {{"dataset"}, {"method"}, {"bin"}, {"pairs"}, {"PSNR difference (dB)"}, {"holes"}, {"cracks"}};
  } else {
    t.columns = {{"dataset"},          {"method"}, {"reference"}, {"PSNR difference (dB)"},
                 {"LPIPS difference"}, {"holes"},  {"cracks"},    {"Gaussians, ratio", 2}};
  }
  for (const auto& d : differences) {
    if ((d.bin != "all") != per_bin) continue;
    if (per_bin)
      t.add({d.dataset, d.method.label(), d.bin, d.psnr.n, interval_text(d.psnr, 2), interval_text(d.holes, 2),
             interval_text(d.cracks, 2)});
    else
      t.add({d.dataset, d.method.label(), d.reference, interval_text(d.psnr, 2), interval_text(d.lpips, 3),
             interval_text(d.holes, 2), interval_text(d.cracks, 2), d.gaussians});
  }
  return t;
}

std::string differences_section(const std::vector<DiffRow>& differences) {
  std::string md =
      "## Differences to the reference, on the same pairs\n\nPaired bootstrap 95% intervals (2000 resamples); an "
      "interval that contains 0 is no difference. Holes and cracks in percentage points (n/a where a method does not "
      "render or the data has no depth).\n\n" +
      table_markdown(differences_markdown(differences, false));
  if (const Table per_bin = differences_markdown(differences, true); !per_bin.rows.empty())
    md += "\nPer baseline bin:\n\n" + table_markdown(per_bin);
  return md + "\n";
}

// differences.csv: every difference with its interval's bounds.
Table differences_table(const std::vector<DiffRow>& differences) {
  Table t;
  t.columns = {{"dataset"}};
  add_method_columns(t);
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"bin"}, {"reference"}, {"pairs"}})
    t.columns.push_back(c);
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"psnr_diff", 4},
                                                                 {"psnr_lo", 4},
                                                                 {"psnr_hi", 4},
                                                                 {"lpips_diff", 5},
                                                                 {"lpips_lo", 5},
                                                                 {"lpips_hi", 5},
                                                                 {"holes_pp", 4},
                                                                 {"holes_lo", 4},
                                                                 {"holes_hi", 4},
                                                                 {"cracks_pp", 4},
                                                                 {"cracks_lo", 4},
                                                                 {"cracks_hi", 4}})
    t.columns.push_back(c);
  t.columns.push_back({"gaussians_ratio", 4});
  for (const auto& d : differences) {
    std::vector<TableCell> cells = {d.dataset};
    add_method_cells(cells, d.method);
    cells.insert(cells.end(), {d.bin, d.reference, d.psnr.n});
    for (const Interval* i : {&d.psnr, &d.lpips, &d.holes, &d.cracks})
      cells.insert(cells.end(), {i->mean, i->lo, i->hi});
    cells.push_back(d.gaussians);
    t.add(std::move(cells));
  }
  return t;
}

// slopes.csv: each sweep's PSNR slope with its interval.
Table slopes_table(const std::vector<SweepSlope>& slopes) {
  Table t;
  t.columns = {{"dataset"}, {"sweep"}, {"unit"}, {"pairs"}, {"slope_db", 4}, {"slope_lo", 4}, {"slope_hi", 4}};
  for (const auto& s : slopes) t.add({s.dataset, s.family, s.unit, s.slope.n, s.slope.mean, s.slope.lo, s.slope.hi});
  return t;
}

// report.csv and report.json: every row with every measure.
Table summary_table(const std::vector<ReportRow>& rows, const std::vector<std::string>& nets) {
  Table t;
  t.columns = {{"dataset"}};
  add_method_columns(t);
  for (const TableColumn& c :
       std::initializer_list<TableColumn>{{"bin"}, {"pairs"}, {"requested"}, {"psnr", 4}, {"ssim", 5}})
    t.columns.push_back(c);
  for (const auto& n : nets) t.columns.push_back({"lpips_" + n, 5});
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"infer_ms", 2},
                                                                 {"render_ms", 2},
                                                                 {"gaussians", 0},
                                                                 {"decoded", 0},
                                                                 {"peak_mb", 1},
                                                                 {"work_mb", 2},
                                                                 {"hole_rate", 5},
                                                                 {"crack_rate", 5},
                                                                 {"normal_deg", 3}})
    t.columns.push_back(c);
  for (const char* st : kStages) t.columns.push_back({std::string(st) + "_ms", 2});
  std::set<std::string> pruning;  // what pruning counted, in any row
  for (const auto& r : rows)
    for (const auto& kv : r.prune_counts) pruning.insert(kv.first);
  for (const auto& k : pruning) t.columns.push_back({"prune_" + k, 1});
  // Columns of measures that were taken, so reports without them keep their columns.
  const bool scaled = std::any_of(rows.begin(), rows.end(), [](const ReportRow& r) { return r.scale_pairs > 0; });
  const bool dense = std::any_of(rows.begin(), rows.end(),
                                 [](const ReportRow& r) { return r.unprompted.pixels > 0 || r.removed.pixels > 0; });
  if (scaled)
    for (const TableColumn& c : std::initializer_list<TableColumn>{{"scale", 6}, {"scale_spread", 6}, {"scale_pairs"}})
      t.columns.push_back(c);
  if (dense)
    for (const TableColumn& c : std::initializer_list<TableColumn>{{"densify_unprompted_abs_rel", 5},
                                                                   {"densify_unprompted_delta1", 5},
                                                                   {"densify_removed_abs_rel", 5},
                                                                   {"densify_removed_delta1", 5}})
      t.columns.push_back(c);
  for (const auto& r : rows) {
    std::vector<TableCell> cells = {r.dataset};
    add_method_cells(cells, r.method);
    cells.insert(cells.end(), {r.bin, r.pairs, r.requested, r.psnr, r.ssim});
    for (const auto& n : nets) cells.push_back(r.lpips.at(n));
    cells.insert(cells.end(), {r.infer_ms, r.render_ms, r.gaussians, r.decoded, r.peak_mb, r.work_mb, r.hole_rate,
                               r.crack_rate, r.normal_deg});
    for (const char* st : kStages) cells.push_back(r.stage_ms.count(st) ? TableCell(r.stage_ms.at(st)) : TableCell());
    for (const auto& k : pruning)
      cells.push_back(r.prune_counts.count(k) ? TableCell(r.prune_counts.at(k)) : TableCell());
    if (scaled) cells.insert(cells.end(), {r.scale, r.scale_spread, r.scale_pairs});
    if (dense)
      cells.insert(cells.end(), {r.unprompted.abs_rel, r.unprompted.delta1, r.removed.abs_rel, r.removed.delta1});
    t.add(std::move(cells));
  }
  return t;
}
}  // namespace

void write_reports(const std::string& out, const std::vector<ReportRow>& rows, const std::vector<std::string>& nets,
                   const std::vector<std::string>& notes, const std::vector<DiffRow>& differences,
                   const std::vector<ReportRow>& breakdowns, const std::vector<SweepSlope>& slopes) {
  const fs::path dir(out);
  std::string md =
      cat("# Evaluation report\n\nMasked metrics on the protocol's pairs (DESIGN §5). PSNR and SSIM higher is better, "
          "LPIPS lower is better. Times are per pair on this machine. Report written by commit ",
          build_commit(), " (scores resumed from earlier runs keep the commit that computed them).\n\n");
  for (const auto& d : datasets_of(rows)) md += dataset_section(rows, d, nets, slopes, breakdowns);
  if (!differences.empty()) {
    md += differences_section(differences);
    write_table_csv((dir / "differences.csv").string(), differences_table(differences));
  }
  if (!slopes.empty()) write_table_csv((dir / "slopes.csv").string(), slopes_table(slopes));
  if (const Table regions = regions_table(rows, true); !regions.rows.empty()) {
    md +=
        "## By image region\n\nMeans over pairs (scoring.regions): each region's share of the scored pixels, "
        "PSNR, LPIPS, detail (the render's Laplacian energy over the target's: below 1 is blurrier) and Gaussian "
        "centres per pixel; source_view is the scene rendered from the source camera against the photo.\n\n" +
        table_markdown(regions) + "\n";
    write_table_csv((dir / "by_region.csv").string(), regions_table(rows, false));
  }
  if (!notes.empty()) {
    md += "## Notes\n\n";
    for (const auto& n : notes) md += "- " + n + "\n";
  }
  write_file_atomic((dir / "report.md").string(), md);
  const Table summary = summary_table(rows, nets);
  write_table_csv((dir / "report.csv").string(), summary);
  write_table_json((dir / "report.json").string(), summary);
  write_charts((dir / "speed_quality.png").string(), reporting::speed_quality_charts(rows), 2, 620, 420);
  const auto stability = reporting::stability_charts(rows);
  if (!stability.empty()) write_charts((dir / "stability.png").string(), stability, 4, 360, 260);
  if (!breakdowns.empty()) {
    write_charts((dir / "baseline.png").string(), reporting::baseline_charts(breakdowns), 2, 560, 380);
    write_table_csv((dir / "breakdown.csv").string(), breakdown_table(breakdowns, "", nets, false));
  }
}

}  // namespace isplat
