#include "planner/budget.hpp"

#include <ios>
#include <sstream>

namespace staa {

std::string BudgetSpec::describe() const {
  if (isExpansions()) return std::to_string(expansions) + " expansions";
  std::ostringstream s;  // the classic locale: "19.00", never "19,00"
  s.setf(std::ios::fixed);
  s.precision(2);
  s << ms << " ms";
  return s.str();
}

}  // namespace staa
