// The report's breakdown by image region (scoring.regions): by_region.csv and its section of report.md.
#include "eval/report.h"
#include "eval/report_parts.h"

namespace isplat {

Table regions_table(const std::vector<ReportRow>& rows, bool markdown) {
  Table t;
  t.columns = {{"dataset"}};
  if (markdown)
    t.columns.push_back({"method"});
  else
    reporting::add_method_columns(t);
  if (!markdown) t.columns.push_back({"bin"});
  const int p = markdown ? 3 : 5;  // digits
  for (const TableColumn& c : std::initializer_list<TableColumn>{{"region"},
                                                                 {"share", p},
                                                                 {"psnr", markdown ? 2 : 4, "PSNR"},
                                                                 {"lpips", p + 1, "LPIPS"},
                                                                 {"detail", p},
                                                                 {"density", p}})
    t.columns.push_back(c);
  for (const auto& r : rows) {
    if (markdown && r.bin != "all") continue;
    for (const auto& [name, g] : r.regions) {
      std::vector<TableCell> cells = {r.dataset};
      if (markdown)
        cells.push_back(r.method.label());
      else
        reporting::add_method_cells(cells, r.method), cells.push_back(r.bin);
      cells.insert(cells.end(), {name, g.share, g.psnr, g.lpips, g.detail, g.density});
      t.add(std::move(cells));
    }
  }
  return t;
}

}  // namespace isplat
