#pragma once
// A run's identification (run_record.h) as `rths identify RECORD.rthsrec` prints it: text, and
// the same figures as JSON (`--json`). Formatters only: every figure is the identification's own,
// computed once by identify_run_record (the findings, each effect's parameters), so one effect has
// one magnitude in every section and in the JSON.
//
// Input: a RunIdentification. Output, in order:
//   the record (case, clock, how much it held, steps and duration), the re-run's inputs;
//   a real-time record's overruns and verdict, and the answers the loop used;
//   per link: the round trip beyond the injected lag (ms) and its undeclared effects;
//   per actuator: declared and fitted gain and delay, each channel's held-out error (a share of
//   the signal's std) with its added effects and their parameters, the sensors' noise, the
//   specimen against the declared storey model, and the effects the form-free description of
//   their channel's residual beat on held-out data (named nowhere: "described, not named");
//   the re-run's NRMSE per floor (declared -> identified) with what each link and effect removes;
//   the findings, every part (findings.h), and what the re-run leaves unexplained;
//   what each channel's model leaves, described without presuming an effect (unexplained.h):
//   "unexplained on PART (CHANNEL): SIGNATURE; share X %", or none;
//   the re-run's response against its floor (response_floor.h), and where above, what locates it.
// One finding, one magnitude: a channel's or a link's own part of its held-out error is printed
// "held-out share" (JSON heldout_share), never "share", which is the re-run's (the findings' and
// the residual's; null in the findings' JSON for a finding not re-run, where it was a 0 beside a
// link's held-out share of the same finding).
// JSON keys: record, case, clock, held, inputs, steps, duration_s, links, actuators, residual,
// undeclared (the findings), unexplained (Unexplained::json, [] when none; with the response
// floor's entry where silent, ResponseFloor::unexplained_json), response_floor
// (ResponseFloor::json), platform, answers_used.

#include <nlohmann/json.hpp>

#include <string>

#include "identify/run/run_record.h"

namespace rths::identify {

std::string run_record_text(const RunIdentification& run);
nlohmann::json run_record_json(const RunIdentification& run);

}  // namespace rths::identify
