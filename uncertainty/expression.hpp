// Measurement models written as text ("l_s + d - l_s*(dalpha*theta + alpha_s*dtheta)"), for
// user models in `probeloop gum` (docs/uncertainty.md#expression-models).
//
// Contract:
// - Grammar: numbers (1, 2.5, 1e-6), input names ([A-Za-z_][A-Za-z0-9_]*), the constant pi,
//   + - * / ^ (power, right-associative, binds tighter than unary minus: -x^2 = -(x^2)),
//   parentheses, and the functions sqrt exp log log10 sin cos tan asin acos atan abs (one
//   argument), atan2 pow hypot (two). Angles are radians.
// - parse() throws ExpressionError with the 1-based column of the offending character and
//   what was expected; an unknown name lists the names that are known.
// - evaluate<T>() works for double and for ceres::Jet (sensitivities by automatic
//   differentiation); gradient() returns the value and the partial derivatives of any number
//   of inputs.
#pragma once
#include <ceres/jet.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace probeloop::uncertainty {

class ExpressionError : public std::runtime_error {
 public:
  ExpressionError(int column, const std::string& message)
      : std::runtime_error("column " + std::to_string(column) + ": " + message), column_(column) {}
  int column() const { return column_; }

 private:
  int column_;
};

class Expression {
 public:
  // symbols: the names the text may use, in the order of the input vector.
  static Expression parse(const std::string& text, const std::vector<std::string>& symbols);

  template <class T>
  T evaluate(const T* x) const { return eval<T>(root_, x); }

  // Value and d(value)/d(x_i) for all inputs, by ceres::Jet in chunks of 8 inputs.
  double gradient(const double* x, std::vector<double>& dydx) const;

  const std::string& text() const { return text_; }

 private:
  enum class Op { Number, Symbol, Neg, Add, Sub, Mul, Div, Pow, Call1, Call2 };
  enum class Fn { Sqrt, Exp, Log, Log10, Sin, Cos, Tan, Asin, Acos, Atan, Abs, Atan2, PowF, Hypot };
  struct Node {
    Op op = Op::Number;
    double value = 0;
    int symbol = -1;
    Fn fn = Fn::Sqrt;
    int a = -1, b = -1;
  };
  friend class ExpressionParser;

  template <class T>
  T eval(int n, const T* x) const {
    const Node& node = nodes_[static_cast<std::size_t>(n)];
    using std::abs, std::acos, std::asin, std::atan, std::atan2, std::cos, std::exp, std::hypot,
        std::log, std::log10, std::pow, std::sin, std::sqrt, std::tan;
    switch (node.op) {
      case Op::Number: return T(node.value);
      case Op::Symbol: return x[node.symbol];
      case Op::Neg: return -eval<T>(node.a, x);
      case Op::Add: return eval<T>(node.a, x) + eval<T>(node.b, x);
      case Op::Sub: return eval<T>(node.a, x) - eval<T>(node.b, x);
      case Op::Mul: return eval<T>(node.a, x) * eval<T>(node.b, x);
      case Op::Div: return eval<T>(node.a, x) / eval<T>(node.b, x);
      case Op::Pow: return powerOf(eval<T>(node.a, x), nodes_[static_cast<std::size_t>(node.b)], node.b, x);
      case Op::Call1: {
        const T v = eval<T>(node.a, x);
        switch (node.fn) {
          case Fn::Sqrt: return sqrt(v);
          case Fn::Exp: return exp(v);
          case Fn::Log: return log(v);
          case Fn::Log10: return log10(v);
          case Fn::Sin: return sin(v);
          case Fn::Cos: return cos(v);
          case Fn::Tan: return tan(v);
          case Fn::Asin: return asin(v);
          case Fn::Acos: return acos(v);
          case Fn::Atan: return atan(v);
          case Fn::Abs: return abs(v);
          default: break;
        }
        break;
      }
      case Op::Call2: {
        const T u = eval<T>(node.a, x), v = eval<T>(node.b, x);
        switch (node.fn) {
          case Fn::Atan2: return atan2(u, v);
          case Fn::PowF: return pow(u, v);
          case Fn::Hypot: return hypot(u, v);
          default: break;
        }
        break;
      }
    }
    return T(std::nan(""));
  }

  // A constant exponent keeps pow(x, 2) defined (and differentiable) for x <= 0.
  template <class T>
  T powerOf(const T& base, const Node& e, int en, const T* x) const {
    using std::pow;
    if (e.op == Op::Number) return pow(base, e.value);
    return pow(base, eval<T>(en, x));
  }

  std::string text_;
  std::vector<Node> nodes_;
  int root_ = -1;
};

}  // namespace probeloop::uncertainty
