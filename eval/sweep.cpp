// Sweep points and method labels.
#include "eval/sweep.h"

#include <cmath>

#include "core/config.h"
#include "core/error.h"

namespace isplat {

void SweepPoint::visit(ConfigVisitor& v) {
  v.field("key", key, "value sweep: the swept key (sweep_key) of this point; empty = not a value sweep");
  v.field("budget", budget, "support-budget sweep: the budget kind of this point; empty = not a budget point",
          {"", "px", "n", "detail"});
  v.field("value", value, "the swept key's value or the budget's number at this point");
}

std::string SweepPoint::axis() const {
  return budget.empty() ? key.substr(key.rfind('.') + 1) : budget;
}

bool SweepPoint::operator==(const SweepPoint& o) const {
  return key == o.key && budget == o.budget && (!any() || value == o.value);
}

std::string MethodId::label() const {
  if (!sweep.any()) return name;
  if (sweep.budget == "n") return cat(name, "@n", std::llround(sweep.value));  // a count: 1000000, not 1e+06
  return cat(name, sweep.budget.empty() ? "~" : "@", sweep.axis(), sweep.value);
}

std::string MethodId::family() const {
  return sweep.any() ? name + " " + sweep.axis() : name;
}

}  // namespace isplat
