#pragma once
// An arithmetic expression of a package's manifest ("ceil(width / 16) * 4"), parsed by muParser.
// Variables are named per evaluation; functions beyond muParser's own: ceil, floor.
#include <map>
#include <string>

namespace bokeh::package {

using Variables = std::map<std::string, double>;

class Expression {
 public:
  Expression() = default;
  // `where` names the expression in errors ("passes[1].invocations[0] of ./my_dof/bokeh-package.json").
  Expression(std::string text, std::string where) : text_(std::move(text)), where_(std::move(where)) {}
  bool empty() const { return text_.empty(); }
  const std::string& text() const { return text_; }
  // Throws std::invalid_argument naming `where`, the text and muParser's message (a syntax error, an
  // unknown variable), or a result that is NaN or infinite.
  double evaluate(const Variables& variables) const;
  // As evaluate, and the value must be a whole number >= 0 (a grid size, a count of elements).
  double count(const Variables& variables) const;

 private:
  std::string text_, where_;
};

}  // namespace bokeh::package
