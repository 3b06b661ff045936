// Which method scored a result: its configured name and the sweep point it was expanded to. Budgets and value
// sweeps travel as these typed fields (evaluator, results log, reports); the label is generated from them for
// file names and for readers, and never read back.
#pragma once
#include <limits>
#include <string>

namespace isplat {

class ConfigVisitor;

struct SweepPoint {
  std::string key;     // value sweep: the swept key as configured (perturb.depth_noise, override:prior.sparse.noise)
  std::string budget;  // support-budget sweep: px | n | detail
  double value = 0;    // the key's value or the budget's number (with a key or a budget)
  void visit(ConfigVisitor& v);
  bool any() const { return !key.empty() || !budget.empty(); }
  // The axis a sweep's points share: the budget kind ("px") or the key's last part ("depth_noise").
  std::string axis() const;
  bool operator==(const SweepPoint& o) const;  // values compare exactly, and only where there is a sweep
};

struct MethodId {
  std::string name;  // as configured (methods[].name)
  SweepPoint sweep;  // none for a method that was not expanded
  // "full", "full@px0.5" (budget), "full~depth_noise0.02" (value sweep): results file names, report.md and logs.
  std::string label() const;
  // "full px", "full depth_noise": the series a sweep's points form (charts, slopes); the name without a sweep.
  std::string family() const;
  bool operator==(const MethodId& o) const { return name == o.name && sweep == o.sweep; }
  bool operator!=(const MethodId& o) const { return !(*this == o); }
  bool operator<(const MethodId& o) const { return label() < o.label(); }  // reports list methods by label
};

}  // namespace isplat
