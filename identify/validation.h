#pragma once
// Validation of an identified channel model that a reviewer accepts.
//
//   kfold           the record cut into k contiguous blocks; for each block the model's structure
//                   is refitted (from the identified parameters) on the other k-1 blocks and its
//                   error measured on the block left out. Reported: the k held-out errors, their
//                   mean and spread (sample standard deviation), and each parameter's mean and
//                   spread over the folds (an uncertainty that, unlike the Jacobian's, sees the
//                   coloured residuals of a real record). Beside each fold's error, the noise
//                   floor of its block (evidence.h noise_floor): a fold where the signal is small
//                   against the sensor noise cannot reach the others' error, whatever the model.
//   validate_on     the model carried to another record of the same rig: physical parameters
//                   fixed, record-specific ones (offset, drift, drift coefficients; ParamSpec::
//                   record_specific) re-estimated on it; error over the whole other record.
// Errors are normalised as everywhere in identify (model.h normalised_error).

#include <string>
#include <vector>

#include "identify/fit.h"

namespace rths::identify {

struct KFoldResult {
  std::vector<double> heldout_errors;  // one per fold
  std::vector<double> noise_floors;    // one per fold, of the held-out block
  double mean = 0.0, spread = 0.0;
  std::vector<std::string> param_names;
  std::vector<double> param_mean, param_spread;  // SI, over the folds
};

// @pre folds >= 2 and every block has at least 50 samples; throws std::invalid_argument otherwise.
KFoldResult kfold(const ChannelModel& model, const ChannelSignals& signals, std::size_t folds,
                  const FitOptions& options = {});

struct CrossRecordResult {
  std::string source;
  double error = 0.0;  // over the whole other record
  FitResult fit;
};
CrossRecordResult validate_on(const ChannelModel& model, const ChannelSignals& other,
                              const std::string& source);

}  // namespace rths::identify
