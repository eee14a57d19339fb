#include "expression.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <muParser.h>

namespace bokeh::package {

double Expression::evaluate(const Variables& variables) const {
  Variables values = variables;  // muParser reads variables through pointers to doubles it may not change
  double result = 0;
  try {
    mu::Parser parser;
    parser.DefineFun("ceil", static_cast<double (*)(double)>([](double x) { return std::ceil(x); }));
    parser.DefineFun("floor", static_cast<double (*)(double)>([](double x) { return std::floor(x); }));
    for (auto& [name, value] : values) parser.DefineVar(name, &value);
    parser.SetExpr(text_);
    result = parser.Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw std::invalid_argument(fmt::format("{}: '{}': {}", where_, text_, e.GetMsg()));
  }
  if (!std::isfinite(result)) throw std::invalid_argument(fmt::format("{}: '{}' is {} here", where_, text_, result));
  return result;
}

double Expression::count(const Variables& variables) const {
  const double value = evaluate(variables);
  if (value < 0 || value != std::floor(value))
    throw std::invalid_argument(fmt::format("{}: '{}' is {}, not a whole number >= 0", where_, text_, value));
  return value;
}

}  // namespace bokeh::package
