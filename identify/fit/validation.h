#pragma once
// Validation of an identified channel model that a reviewer accepts.
//
//   kfold           the record cut into k contiguous blocks; for each block the model's structure
//                   is refitted on the other k-1 blocks, every fold from the same starting point
//                   (the identified parameters), and its error measured on the block left out.
//                   Every fold's error is normalised by the same scale, the standard deviation of
//                   the target over the whole record:  e_f = RMS_f(target - prediction) / std(target)
//                   (as the in-record held-out error, whose held-out blocks span the record). A
//                   fold's own std would not do: on a chirp the actuator realises a third of the
//                   command at the fast end, so the same residual would count three times as much
//                   there, and the spread would measure the signal's envelope, not the model.
//                   Reported: the k held-out errors, their mean and spread (the sample standard
//                   deviation, k - 1 in the denominator), each fold's error also by its block's own
//                   std (block_errors, for comparison), and each parameter's mean and spread over
//                   the folds (an uncertainty that, unlike the Jacobian's, sees the coloured
//                   residuals of a real record). Beside each fold's error, the noise floor of its
//                   block (evidence.h noise_floor), normalised the same way (by the record's std):
//                   no fold can go below it, whatever the model; 0 when the block has no band free
//                   of signal to estimate it from.
//   validate_on     the model carried to another record of the same rig: physical parameters
//                   fixed, record-specific ones (offset, drift, drift coefficients; ParamSpec::
//                   record_specific) re-estimated on it; error over the whole other record.
// validate_on's error is normalised as everywhere in identify (model.h normalised_error).

#include <functional>
#include <string>
#include <vector>

#include "identify/fit/fit.h"

namespace rths::identify {

struct KFoldResult {
  std::vector<double> heldout_errors;  // one per fold, RMS residual / std(target over the record)
  std::vector<double> block_errors;    // one per fold, RMS residual / std(target over the block)
  std::vector<double> noise_floors;    // one per fold, of the held-out block, / std over the record
  double mean = 0.0, spread = 0.0;     // of heldout_errors; spread = sample standard deviation
  std::vector<std::string> param_names;
  std::vector<double> param_mean, param_spread;  // SI, over the folds
};

// @pre folds >= 2 and every block has at least 50 samples; throws std::invalid_argument otherwise.
// `on_fold`, when set, is called with the number of folds done after each fold's fit.
KFoldResult kfold(const ChannelModel& model, const ChannelSignals& signals, std::size_t folds,
                  const FitOptions& options = {},
                  const std::function<void(std::size_t folds_done)>& on_fold = {});

struct CrossRecordResult {
  std::string source;
  double error = 0.0;  // over the whole other record
  FitResult fit;
};
CrossRecordResult validate_on(const ChannelModel& model, const ChannelSignals& other,
                              const std::string& source);

}  // namespace rths::identify
