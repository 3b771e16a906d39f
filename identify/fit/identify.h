#pragma once
// The whole identification of a lab record: both channels, search on a decimated copy (fast),
// every reported error and parameter refitted and measured at the full rate.
//
// Per channel: declared model fitted -> greedy forward selection (selection.h) on the decimated
// record, every fit capped by cost (IdentifyOptions::search_tolerance, search_iterations) -> the
// declared model and each step's model refitted jointly at the full rate, starting from the
// search's parameters; the step's errors before/after are those full-rate fits.
// The threshold and parameter penalty are applied on the search data (where decimation has
// averaged the sensor noise); at the full rate a step must still lower the held-out error, or it
// and the steps after it are dropped (listed in ChannelIdentification::dropped_at_full_rate).

#include <functional>
#include <string>
#include <vector>

#include "identify/fit/selection.h"

namespace rths::identify {

// Progress of identify(): `done` of `total` units of work. Per channel: its search's units
// (selection.h selection_units: the declared fit, each candidate of each round, the specimen
// kinds) and one for the refit at the full rate. `done` never decreases and ends at `total`;
// `stage` says what runs ("force: candidate bouc_wen (round 2)", "force: full-rate refit"); it is
// reported again after every solver iteration, so progress moves while one fit runs long.
struct IdentifyProgress {
  std::size_t done = 0, total = 0;
  std::string stage;
};

struct IdentifyOptions {
  std::vector<Channel> channels{Channel::kMeasured, Channel::kForce};
  std::vector<Effect> declared_actuator{Effect::kDelay};
  std::vector<Effect> declared_specimen{Effect::kStiffness};
  // A declared model's initial values, bounds and fixed parameters
  // (identify/model/declared_model.h).
  std::vector<ParamDeclaration> actuator_parameters, specimen_parameters;
  double holdout_fraction = 0.3;
  HoldoutMode holdout_mode = HoldoutMode::kBlocks;
  std::size_t holdout_blocks = 10;
  // Decimation factor for the search; 0 chooses one that leaves at most ~search_samples samples.
  std::size_t search_decimation = 0;
  std::size_t search_samples = 12000;
  // The cost cap of every fit of a decimated search: its ranking only has to tell which effect
  // pays by the threshold (a few %), and every step it keeps is refitted at the full rate to
  // selection.fit's own tolerance from where the search left it.
  double search_tolerance = 1e-6;
  int search_iterations = 30;
  SelectionOptions selection;
  // Called as the work proceeds (IdentifyProgress); empty = silent. selection.progress is set by
  // identify() itself.
  std::function<void(const IdentifyProgress&)> progress;
};

// The total units identify() reports for these options.
std::size_t identify_units(const IdentifyOptions& options);

struct Identification {
  std::string source;
  std::size_t samples = 0;
  double dt = 0.0;
  std::size_t search_decimation = 1;
  Split split;  // at the full rate
  std::vector<ChannelIdentification> channels;
  std::vector<ChannelSignals> signals;  // at the full rate, one per channel
  const ChannelIdentification* find(Channel channel) const;
  // All steps of all channels in order (measured first).
  std::vector<const SelectionStep*> steps() const;
};

Identification identify(const MeasuredData& data, const IdentifyOptions& options = {});

// A record's force column is required when `channels` holds the force channel, optional otherwise
// (the actuator channel alone needs command and measured displacement).
ForceColumn force_column(const std::vector<Channel>& channels);

}  // namespace rths::identify
