#pragma once
// The coordinator program:
//   rths-coordinator --config STUDY [--case NAME] [--run-id ID] [--record FILE] [--domain D]
//                    [--security DIR/node_0]   (DDS Security; bad documents: exit 2, nothing sent)
//                    [--secret-file FILE | --insecure]  (the run secret, security/run_secret.h:
//                    else $RTHS_RUN_SECRET_FILE or $RTHS_RUN_SECRET; with none and neither DDS
//                    Security nor --insecure: exit 2 naming why, before DDS starts)
//                    [--platform FILE | --platform-seconds S] [--accept-platform]
// A real-time run first checks the platform (rt_check/check.h: measured for S s, default 3, or
// read from FILE), refuses with exit 3 naming the numbers and the fix when the deployment's
// fail-safe or overrun tolerance will not hold (unless --accept-platform), holds
// /dev/cpu_dma_latency at 0 for the run when permitted, and records the check in the header.
//                    [--view HOST:PORT [--view-stop]]  (the live view, view/server.h; needs
//                    --record; the stop button HOLDs then STOPs the run, "stopped from the view";
//                    it needs the token in the address printed at start-up, loopback included)
// Loads the study, opens DDS (domain: --domain, else deployment.domain_id), runs one case and
// prints a summary. SIGXFSZ is ignored: a file size limit fails the record's write, which stops
// the run as a full disk does (HOLD, what the record took, the reason). Exit: 0 completed, 1 the
// run stopped (node lost, limit, start-up timeout), 2 bad config or usage, 3 DDS or file error.

#include <string>

#include "coordinator/coordinator.h"

namespace rths::coordinator {

int coordinator_main(int argc, char** argv);

// One line per fact: status, steps, rejected messages, overruns, the loop's CPU time per step
// ("loop CPU per step: median X ms, p99 Y ms, max Z ms over N steps"), lag per link.
std::string summary_text(const RunOutcome& outcome);

}  // namespace rths::coordinator
