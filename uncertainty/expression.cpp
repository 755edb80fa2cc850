#include "uncertainty/expression.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>

namespace probeloop::uncertainty {

// Recursive descent over:  sum := product (('+'|'-') product)*
//                          product := unary (('*'|'/') unary)*
//                          unary := '-' unary | '+' unary | power
//                          power := primary ('^' unary)?
//                          primary := number | name | name '(' sum (',' sum)? ')' | '(' sum ')'
class ExpressionParser {
 public:
  ExpressionParser(const std::string& text, const std::vector<std::string>& symbols, Expression& e)
      : s_(text), symbols_(symbols), e_(e) {}

  int parseAll() {
    skip();
    if (pos_ >= s_.size()) fail(pos_, "the expression is empty");
    const int root = sum();
    skip();
    if (pos_ < s_.size())
      fail(pos_, "unexpected '" + characterAt(pos_) + "': expected an operator (+ - * / ^) or the end");
    return root;
  }

 private:
  using Op = Expression::Op;
  using Fn = Expression::Fn;

  [[noreturn]] void fail(std::size_t at, const std::string& m) { throw ExpressionError(static_cast<int>(at) + 1, m); }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skip();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  int add(Expression::Node n) {
    // Bounded, so evaluation (recursive over the tree) cannot exhaust the stack.
    if (e_.nodes_.size() >= 10000) fail(pos_, "the expression is too long (more than 10000 terms)");
    e_.nodes_.push_back(n);
    return static_cast<int>(e_.nodes_.size()) - 1;
  }
  int binary(Op op, int a, int b) {
    Expression::Node n;
    n.op = op;
    n.a = a;
    n.b = b;
    return add(n);
  }

  int sum() {
    int left = product();
    for (;;) {
      if (accept('+')) left = binary(Op::Add, left, product());
      else if (accept('-')) left = binary(Op::Sub, left, product());
      else return left;
    }
  }
  int product() {
    int left = unary();
    for (;;) {
      if (accept('*')) left = binary(Op::Mul, left, unary());
      else if (accept('/')) left = binary(Op::Div, left, unary());
      else return left;
    }
  }
  struct Depth {
    explicit Depth(ExpressionParser& p) : p_(p) {
      if (++p_.depth_ > 200) p_.fail(p_.pos_, "the expression is nested too deeply (more than 200 levels)");
    }
    ~Depth() { --p_.depth_; }
    ExpressionParser& p_;
  };

  int unary() {
    Depth guard(*this);
    if (accept('-')) {
      const int v = unary();
      auto& n = e_.nodes_[static_cast<std::size_t>(v)];
      if (n.op == Op::Number) {  // fold: keeps x^-2 a constant exponent
        n.value = -n.value;
        return v;
      }
      Expression::Node neg;
      neg.op = Op::Neg;
      neg.a = v;
      return add(neg);
    }
    if (accept('+')) return unary();
    return power();
  }
  int power() {
    Depth guard(*this);
    const int base = primary();
    if (accept('^')) return binary(Op::Pow, base, unary());
    return base;
  }
  int primary() {
    skip();
    if (pos_ >= s_.size()) fail(pos_, "the expression ends where a number, a name or '(' was expected");
    const char c = s_[pos_];
    if (c == '(') {
      const std::size_t open = pos_++;
      const int v = sum();
      if (!accept(')')) fail(pos_, "expected ')' to close the '(' at column " + std::to_string(open + 1));
      return v;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name();
    fail(pos_, "unexpected '" + characterAt(pos_) + "': expected a number, a name or '('");
  }
  // The whole UTF-8 sequence at i, so a message never prints half a character.
  std::string characterAt(std::size_t i) const {
    std::size_t n = 1;
    while (i + n < s_.size() && (static_cast<unsigned char>(s_[i + n]) & 0xC0) == 0x80) ++n;
    return s_.substr(i, n);
  }
  // digits [. digits] [(e|E) [+-] digits]: scanned here (strtod alone would also take hex,
  // inf and nan).
  int number() {
    const std::size_t start = pos_;
    auto digits = [&] {
      const std::size_t from = pos_;
      while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      return pos_ - from;
    };
    std::size_t mantissa = digits();
    if (pos_ < s_.size() && s_[pos_] == '.') {
      ++pos_;
      mantissa += digits();
    }
    if (mantissa == 0) fail(start, "malformed number: '.' needs digits");
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      const std::size_t e = pos_++;
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
      if (digits() == 0) fail(e, "malformed number: the exponent needs digits (e.g. 1e-6)");
    }
    if (pos_ < s_.size() && (std::isalpha(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_' || s_[pos_] == '.'))
      fail(pos_, "a number runs into '" + characterAt(pos_) + "': write the operator (e.g. 2*x)");
    const double v = std::strtod(s_.substr(start, pos_ - start).c_str(), nullptr);
    if (!std::isfinite(v)) fail(start, "number out of range");
    Expression::Node n;
    n.op = Op::Number;
    n.value = v;
    return add(n);
  }
  int name() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_')) ++pos_;
    const std::string id = s_.substr(start, pos_ - start);
    skip();
    if (pos_ < s_.size() && s_[pos_] == '(') return call(id, start);
    for (std::size_t i = 0; i < symbols_.size(); ++i)
      if (symbols_[i] == id) {
        Expression::Node n;
        n.op = Op::Symbol;
        n.symbol = static_cast<int>(i);
        return add(n);
      }
    if (id == "pi") {
      Expression::Node n;
      n.op = Op::Number;
      n.value = M_PI;
      return add(n);
    }
    std::string known;
    for (const auto& k : symbols_) known += (known.empty() ? "" : ", ") + k;
    fail(start, "unknown name '" + id + "'; the inputs are: " + known + " (and the constant pi)");
  }
  int call(const std::string& id, std::size_t at) {
    static const std::map<std::string, std::pair<Fn, int>> fns = {
        {"sqrt", {Fn::Sqrt, 1}}, {"exp", {Fn::Exp, 1}},     {"log", {Fn::Log, 1}},     {"log10", {Fn::Log10, 1}},
        {"sin", {Fn::Sin, 1}},   {"cos", {Fn::Cos, 1}},     {"tan", {Fn::Tan, 1}},     {"asin", {Fn::Asin, 1}},
        {"acos", {Fn::Acos, 1}}, {"atan", {Fn::Atan, 1}},   {"abs", {Fn::Abs, 1}},     {"atan2", {Fn::Atan2, 2}},
        {"pow", {Fn::PowF, 2}},  {"hypot", {Fn::Hypot, 2}}};
    const auto it = fns.find(id);
    if (it == fns.end())
      fail(at, "unknown function '" + id +
                   "'; known: sqrt exp log log10 sin cos tan asin acos atan abs (1 argument), atan2 pow hypot (2)");
    ++pos_;  // '('
    Expression::Node n;
    n.fn = it->second.first;
    n.a = sum();
    if (it->second.second == 2) {
      if (!accept(',')) fail(pos_, id + " takes two arguments: expected ','");
      n.b = sum();
      n.op = Op::Call2;
    } else {
      n.op = Op::Call1;
      skip();
      if (pos_ < s_.size() && s_[pos_] == ',') fail(pos_, id + " takes one argument");
    }
    if (!accept(')')) fail(pos_, "expected ')' to close " + id + "(");
    return add(n);
  }

  const std::string& s_;
  const std::vector<std::string>& symbols_;
  Expression& e_;
  std::size_t pos_ = 0;
  int depth_ = 0;
};

Expression Expression::parse(const std::string& text, const std::vector<std::string>& symbols) {
  Expression e;
  e.text_ = text;
  ExpressionParser p(text, symbols, e);
  e.root_ = p.parseAll();
  return e;
}

double Expression::gradient(const double* x, std::vector<double>& dydx) const {
  constexpr int kChunk = 8;
  using J = ceres::Jet<double, kChunk>;
  int n = 0;
  for (const auto& node : nodes_) n = std::max(n, node.symbol + 1);
  // n = highest symbol used + 1; the caller's vector may be longer.
  const std::size_t total = dydx.size();
  std::vector<J> xj(total);
  double y = evaluate(x);
  for (std::size_t first = 0; first < static_cast<std::size_t>(n); first += kChunk) {
    for (std::size_t i = 0; i < total; ++i) xj[i] = J(x[i]);
    for (std::size_t i = first; i < std::min<std::size_t>(first + kChunk, total); ++i) xj[i].v(static_cast<int>(i - first)) = 1.0;
    const J r = evaluate(xj.data());
    for (std::size_t i = first; i < std::min<std::size_t>(first + kChunk, total); ++i) dydx[i] = r.v(static_cast<int>(i - first));
  }
  for (std::size_t i = static_cast<std::size_t>(n); i < total; ++i) dydx[i] = 0.0;
  return y;
}

}  // namespace probeloop::uncertainty
