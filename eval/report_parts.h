// Internal to the evaluation report (eval/report*.cpp): method columns, the sweeps' points and strengths, and the
// charts.
#pragma once
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "eval/report.h"
#include "io/chart.h"
#include "io/table.h"

namespace isplat {
namespace reporting {

// The columns that name a method in CSV and JSON: its name and its sweep point as typed fields (report.md shows
// the label instead), and one row's cells for them.
void add_method_columns(Table& t);
void add_method_cells(std::vector<TableCell>& cells, const MethodId& m);

// A value sweep's point on dataset d over all bins (budgets are not value sweeps).
bool is_sweep_point(const ReportRow& r, const std::string& d);

// The value sweeps on dataset d ("full depth_noise"), each as its first point, in the order they first appear.
std::vector<MethodId> sweep_families(const std::vector<ReportRow>& rows, const std::string& d);

// Each perturbation's value that changes nothing (scale and exposure 1, the others 0).
const std::map<std::string, double>& neutral_values();

// A sweep's points (value, field) on dataset d, all bins. When the sweep leaves out the unperturbed value of
// a perturbation (scale and exposure 1, the others 0) and the same method runs unperturbed (the family's
// name without a sweep), that run is the point there.
std::vector<std::pair<double, double>> sweep_points(const std::vector<ReportRow>& rows, const std::string& d,
                                                    const MethodId& family, double ReportRow::*field, double scale = 1);

// How strong a perturbation of `key` is at a swept value (0 = none), and the unit of that strength.
std::pair<std::function<double(double)>, std::string> perturbation_strength(const std::string& key);

// speed_quality.png: per dataset, PSNR against time and against Gaussians, one series per method family, the
// Pareto front marked.
std::vector<Chart> speed_quality_charts(const std::vector<ReportRow>& rows);
// stability.png: per dataset and swept key, PSNR, holes, cracks and normals against the swept value.
std::vector<Chart> stability_charts(const std::vector<ReportRow>& rows);
// baseline.png: per dataset, PSNR and hole rate against the baseline group's centre.
std::vector<Chart> baseline_charts(const std::vector<ReportRow>& breakdowns);

}  // namespace reporting
}  // namespace isplat
