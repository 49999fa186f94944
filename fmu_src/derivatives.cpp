// fmi2GetRealOutputDerivatives and fmi2GetDirectionalDerivative over the
// Simulation (solver/output_derivatives.cpp). Every reference, order and
// seed is checked before anything is computed; the computations leave the
// state, the inputs and the integrator's history as they were.
#include <cmath>

#include "instance.hpp"
#include "math/number_text.hpp"
#include "model_description.hpp"

namespace mfbd {

namespace {

const char* causalityText(Causality c) {
  switch (c) {
    case Causality::Parameter: return "a parameter";
    case Causality::Input: return "an input";
    case Causality::Output: return "an output";
  }
  return "?";
}

}  // namespace

bool Instance::variablesOf(const char* function, const fmi2ValueReference vr[], std::size_t n, Causality causality,
                           std::vector<Quantity>& quantities) {
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = byReference_.find(vr[i]);
    if (it == byReference_.end()) {
      fail(function, "no Real variable with value reference " + std::to_string(vr[i]));
      return false;
    }
    const Variable& v = table_[it->second];
    if (v.causality != causality) {
      fail(function, "'" + v.name + "' is " + causalityText(v.causality) + "; expected " + causalityText(causality) +
                         (causality == Causality::Output ? " (derivatives are of outputs)"
                                                         : " (derivatives are with respect to inputs)"));
      return false;
    }
    quantities.push_back(v.quantity);
  }
  return true;
}

fmi2Status Instance::getRealOutputDerivatives(const fmi2ValueReference vr[], std::size_t n, const fmi2Integer order[],
                                              fmi2Real value[]) {
  const char* function = "fmi2GetRealOutputDerivatives";
  if (n == 0) return fmi2OK;
  if (!vr || !order || !value) return fail(function, "null array argument");
  const int maxOrder = maxOutputDerivativeOrder(scene_);
  if (maxOrder == 0)
    return fail(function, "not supported for a static analysis (maxOutputDerivativeOrder=0)");
  std::vector<Quantity> outputs;
  if (!variablesOf(function, vr, n, Causality::Output, outputs)) return fmi2Error;
  std::vector<int> orders;
  for (std::size_t i = 0; i < n; ++i) {
    if (order[i] < 1 || order[i] > maxOrder)
      return fail(function, "order " + std::to_string(order[i]) + " of '" + table_[byReference_[vr[i]]].name +
                                "': expected 1 to " + std::to_string(maxOrder) + " (maxOutputDerivativeOrder)");
    orders.push_back(order[i]);
  }
  if (state_ == FmuState::Error || !simulation_)
    return fail(function, "outputs have no value in this state (the initialization failed; see the earlier error)");
  const std::vector<double> d = simulation_->outputDerivatives(outputs, orders);
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(d[i]))
      return fail(function, "derivative of order " + std::to_string(order[i]) + " of '" +
                                table_[byReference_[vr[i]]].name + "' is not finite");
  for (std::size_t i = 0; i < n; ++i) value[i] = d[i];
  return fmi2OK;
}

fmi2Status Instance::getDirectionalDerivative(const fmi2ValueReference unknown[], std::size_t nUnknown,
                                              const fmi2ValueReference known[], std::size_t nKnown,
                                              const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
  const char* function = "fmi2GetDirectionalDerivative";
  if ((nUnknown > 0 && (!unknown || !dvUnknown)) || (nKnown > 0 && (!known || !dvKnown)))
    return fail(function, "null array argument");
  if (!providesDirectionalDerivative(scene_))
    return fail(function, "not supported for a static analysis (providesDirectionalDerivative=false)");
  std::vector<Quantity> outputs, inputs;
  if (!variablesOf(function, unknown, nUnknown, Causality::Output, outputs) ||
      !variablesOf(function, known, nKnown, Causality::Input, inputs))
    return fmi2Error;
  std::vector<double> seed(dvKnown, dvKnown + nKnown);
  for (std::size_t j = 0; j < nKnown; ++j)
    if (!std::isfinite(seed[j]))
      return fail(function, "seed of '" + table_[byReference_[known[j]]].name + "' = " + numberText(seed[j]) +
                                ": expected a finite value");
  if (nUnknown == 0) return fmi2OK;
  if ((simulationStale_ || !simulation_) && state_ == FmuState::InitializationMode && !buildSimulation(function))
    return fmi2Error;
  if (state_ == FmuState::Error || !simulation_)
    return fail(function, "outputs have no value in this state (the initialization failed; see the earlier error)");
  const std::vector<double> d = simulation_->inputDirectionalDerivative(outputs, inputs, seed);
  for (std::size_t i = 0; i < nUnknown; ++i)
    if (!std::isfinite(d[i]))
      return fail(function, "the derivative of '" + table_[byReference_[unknown[i]]].name + "' is not finite");
  for (std::size_t i = 0; i < nUnknown; ++i) dvUnknown[i] = d[i];
  return fmi2OK;
}

}  // namespace mfbd
