#pragma once
// How a front end ends after distributed runs: the exit status of `rths launch` and `rths sites`
// from the judged runs (analysis/distributed/distributed_run.h).

#include <vector>

#include "analysis/distributed/distributed_run.h"

namespace rths::cli {

using analysis::DistributedResults;
using analysis::DistributedRun;

// Exit status of distributed cases: the first failing coordinator's (1 run failed, also when it
// was killed by a signal or stopped at the timeout; 2 bad config; 3 environment), then a case
// that left no record (3), then a lockstep case that differs from the in-process run (1, naming
// the first differing step), then a diverged case (1; unless allow_unstable or expect_unstable).
// Throws ExitError; returns when every case passed.
void fail_if_distributed_failed(const DistributedResults& results,
                                const std::vector<DistributedRun>& runs, bool allow_unstable);

}  // namespace rths::cli
