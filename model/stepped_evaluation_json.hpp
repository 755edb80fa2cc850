// Reading the fields of a stepped workpiece's evaluation.json (evaluate/stepped_workpiece.hpp)
// that the prediction and the thermal stages use: a number, a budget's value and u_c, each
// refused with the file and the field's path when it is missing or not finite.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

namespace probeloop::model {

double evaluationNumber(const nlohmann::json& o, const char* key, const std::string& where, const std::string& file);
// {value, u_c} of a budget (evaluate/budget_json.hpp).
std::pair<double, double> evaluationBudget(const nlohmann::json& o, const char* key, const std::string& where,
                                           const std::string& file);
// InputError unless `e` is the evaluation.json of a stepped workpiece with a separation.
void requireSteppedEvaluation(const nlohmann::json& e, const std::string& file);

}  // namespace probeloop::model
