// Aggregation and report writers (Markdown, CSV, JSON, PNG chart).
#include "eval/report.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/image_io.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {
std::string fmt(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}
}  // namespace

std::vector<ReportRow> summarize(const std::string& dataset, const std::string& method,
                                 const std::vector<std::string>& bin_labels, const std::vector<int64_t>& requested,
                                 const std::vector<PairResult>& results, const std::vector<std::string>& lpips_nets) {
  std::vector<ReportRow> rows;
  auto make = [&](const std::string& label, int bin, int64_t req) {
    ReportRow r;
    r.dataset = dataset;
    r.method = method;
    r.bin = label;
    r.requested = req;
    double p = 0, s = 0, inf = 0, ren = 0, g = 0;
    std::map<std::string, double> lp;
    std::map<std::string, int64_t> lp_n;
    int64_t psnr_n = 0;
    for (const auto& x : results) {
      if (bin >= 0 && x.bin != bin) continue;
      ++r.pairs;
      if (std::isfinite(x.psnr)) p += x.psnr, ++psnr_n;
      s += x.ssim, inf += x.infer_ms, ren += x.render_ms, g += x.gaussians;
      for (const auto& net : lpips_nets) {
        auto it = x.lpips.find(net);
        if (it != x.lpips.end() && std::isfinite(it->second)) lp[net] += it->second, ++lp_n[net];
      }
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double n = static_cast<double>(r.pairs);
    r.psnr = psnr_n ? p / psnr_n : nan;
    r.ssim = r.pairs ? s / n : nan;
    r.infer_ms = r.pairs ? inf / n : nan;
    r.render_ms = r.pairs ? ren / n : nan;
    r.gaussians = r.pairs ? g / n : nan;
    for (const auto& net : lpips_nets) r.lpips[net] = lp_n[net] ? lp[net] / lp_n[net] : nan;
    rows.push_back(r);
  };
  int64_t total_req = 0;
  for (size_t b = 0; b < bin_labels.size(); ++b) {
    make(bin_labels[b], static_cast<int>(b), requested[b]);
    total_req += requested[b];
  }
  make("all", -1, total_req);
  return rows;
}

void write_reports(const std::string& out, const std::vector<ReportRow>& rows, const std::vector<std::string>& nets,
                   const std::vector<std::string>& notes) {
  // Markdown: one table per dataset.
  std::ostringstream md;
  md << "# Evaluation report\n\nMasked metrics on the protocol's pairs (DESIGN §5). PSNR and SSIM higher is better, "
        "LPIPS lower is better. Times are per pair on this machine.\n\n";
  std::vector<std::string> datasets;
  for (const auto& r : rows)
    if (std::find(datasets.begin(), datasets.end(), r.dataset) == datasets.end()) datasets.push_back(r.dataset);
  for (const auto& d : datasets) {
    md << "## " << d << "\n\n| method | bin | pairs | PSNR | SSIM |";
    for (const auto& n : nets) md << " LPIPS (" << n << ") |";
    md << " infer ms | render ms | Gaussians |\n|---|---|---|---|---|";
    for (size_t i = 0; i < nets.size(); ++i) md << "---|";
    md << "---|---|---|\n";
    for (const auto& r : rows) {
      if (r.dataset != d) continue;
      md << "| " << r.method << " | " << r.bin << " | " << r.pairs
         << (r.pairs < r.requested ? cat(" of ", r.requested) : "") << " | " << fmt(r.psnr, 2) << " | "
         << fmt(r.ssim, 4) << " |";
      for (const auto& n : nets) md << " " << fmt(r.lpips.at(n), 4) << " |";
      md << " " << fmt(r.infer_ms, 0) << " | " << fmt(r.render_ms, 0) << " | " << fmt(r.gaussians, 0) << " |\n";
    }
    md << "\n";
  }
  if (!notes.empty()) {
    md << "## Notes\n\n";
    for (const auto& n : notes) md << "- " << n << "\n";
  }
  write_file_atomic((fs::path(out) / "report.md").string(), md.str());

  CsvTable csv;
  csv.header = {"dataset", "method", "bin", "pairs", "requested", "psnr", "ssim"};
  for (const auto& n : nets) csv.header.push_back("lpips_" + n);
  for (const char* h : {"infer_ms", "render_ms", "gaussians"}) csv.header.push_back(h);
  nlohmann::ordered_json js = nlohmann::ordered_json::array();
  for (const auto& r : rows) {
    std::vector<std::string> row = {
        r.dataset,      r.method,      r.bin, std::to_string(r.pairs), std::to_string(r.requested),
        fmt(r.psnr, 4), fmt(r.ssim, 5)};
    nlohmann::ordered_json j = {
        {"dataset", r.dataset}, {"method", r.method}, {"bin", r.bin}, {"pairs", r.pairs}, {"requested", r.requested}};
    j["psnr"] = std::isfinite(r.psnr) ? nlohmann::ordered_json(r.psnr) : nlohmann::ordered_json(nullptr);
    j["ssim"] = std::isfinite(r.ssim) ? nlohmann::ordered_json(r.ssim) : nlohmann::ordered_json(nullptr);
    for (const auto& n : nets) {
      row.push_back(fmt(r.lpips.at(n), 5));
      j["lpips_" + n] =
          std::isfinite(r.lpips.at(n)) ? nlohmann::ordered_json(r.lpips.at(n)) : nlohmann::ordered_json("n/a");
    }
    row.push_back(fmt(r.infer_ms, 2));
    row.push_back(fmt(r.render_ms, 2));
    row.push_back(fmt(r.gaussians, 0));
    j["infer_ms"] = r.infer_ms;
    j["render_ms"] = r.render_ms;
    j["gaussians"] = r.gaussians;
    csv.rows.push_back(row);
    js.push_back(j);
  }
  write_csv((fs::path(out) / "report.csv").string(), csv);
  write_file_atomic((fs::path(out) / "report.json").string(), js.dump(2) + "\n");

  // Speed/quality chart: x = inference + render time per pair (log scale), y = masked PSNR.
  // Colour = method, marker = dataset, so each point reads without a long legend.
  const int W = 960, H = 560, L = 80, R = 230, T = 40, B = 60;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<const ReportRow*> pts;
  std::vector<std::string> methods, sets;
  for (const auto& r : rows) {
    if (r.bin != "all" || !std::isfinite(r.psnr)) continue;
    pts.push_back(&r);
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) methods.push_back(r.method);
    if (std::find(sets.begin(), sets.end(), r.dataset) == sets.end()) sets.push_back(r.dataset);
  }
  if (!pts.empty()) {
    auto xval = [](const ReportRow* r) { return std::log10(std::max(0.1, r->infer_ms + r->render_ms)); };
    double x0 = 1e18, x1 = -1e18, y0 = 1e18, y1 = -1e18;
    for (const auto* r : pts) {
      x0 = std::min(x0, xval(r)), x1 = std::max(x1, xval(r)), y0 = std::min(y0, r->psnr), y1 = std::max(y1, r->psnr);
    }
    x0 = std::floor(x0 - 0.2), x1 = std::ceil(x1 + 0.2), y0 -= 1.0, y1 += 1.0;
    auto px = [&](double x) { return L + static_cast<int>((x - x0) / (x1 - x0) * (W - L - R)); };
    auto py = [&](double y) { return H - B - static_cast<int>((y - y0) / (y1 - y0) * (H - T - B)); };
    const cv::Scalar black(0, 0, 0);
    auto text = [&](const std::string& s, cv::Point p, double scale = 0.45) {
      cv::putText(img, s, p, cv::FONT_HERSHEY_SIMPLEX, scale, black, 1, cv::LINE_AA);
    };
    cv::rectangle(img, {L, T}, {W - R, H - B}, black, 1);
    for (int e = static_cast<int>(x0); e <= static_cast<int>(x1); ++e) {
      cv::line(img, {px(e), H - B}, {px(e), H - B + 5}, black);
      std::ostringstream lab;
      lab << std::pow(10.0, e) << " ms";
      text(e == static_cast<int>(x0) ? "<= " + lab.str() : lab.str(), {px(e) - 22, H - B + 22});
    }
    for (int t = 0; t <= 4; ++t) {
      const double y = y0 + (y1 - y0) * t / 4;
      cv::line(img, {L - 5, py(y)}, {L, py(y)}, black);
      text(fmt(y, 1), {L - 48, py(y) + 5});
    }
    text("time per pair (inference + render), log scale", {L + 150, H - 15}, 0.5);
    text("masked PSNR (dB), average over pairs", {10, T - 15}, 0.5);
    // RGB (write_image takes RGB): the matplotlib "tab10" palette.
    static const cv::Scalar colors[] = {{31, 119, 180},  {255, 127, 14}, {44, 160, 44},   {214, 39, 40},
                                        {148, 103, 189}, {140, 86, 75},  {227, 119, 194}, {127, 127, 127}};
    auto marker = [&](size_t kind, cv::Point p, const cv::Scalar& c) {
      switch (kind % 4) {
        case 0:
          cv::circle(img, p, 7, c, cv::FILLED, cv::LINE_AA);
          break;
        case 1:
          cv::rectangle(img, {p.x - 6, p.y - 6}, {p.x + 6, p.y + 6}, c, cv::FILLED);
          break;
        case 2: {
          std::vector<cv::Point> tri = {{p.x, p.y - 8}, {p.x - 7, p.y + 6}, {p.x + 7, p.y + 6}};
          cv::fillConvexPoly(img, tri, c, cv::LINE_AA);
          break;
        }
        default:
          cv::drawMarker(img, p, c, cv::MARKER_TILTED_CROSS, 14, 3, cv::LINE_AA);
      }
    };
    auto index = [](const std::vector<std::string>& v, const std::string& s) {
      return static_cast<size_t>(std::find(v.begin(), v.end(), s) - v.begin());
    };
    for (const auto* r : pts)
      marker(index(sets, r->dataset), {px(xval(r)), py(r->psnr)}, colors[index(methods, r->method) % 8]);
    int y = T + 10;
    text("method (colour)", {W - R + 15, y}, 0.5);
    for (size_t i = 0; i < methods.size(); ++i) {
      y += 22;
      marker(0, {W - R + 25, y - 5}, colors[i % 8]);
      text(methods[i], {W - R + 40, y});
    }
    y += 34;
    text("dataset (marker)", {W - R + 15, y}, 0.5);
    for (size_t i = 0; i < sets.size(); ++i) {
      y += 22;
      marker(i, {W - R + 25, y - 5}, black);
      text(sets[i], {W - R + 40, y});
    }
  }
  write_image((fs::path(out) / "speed_quality.png").string(), img);
}

}  // namespace isplat
