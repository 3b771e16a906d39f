#pragma once
// Never silent: each identified channel's residual against the floor the record's own noise sets,
// and where it stands above that floor by more than a stated factor, where and when it lies, at
// what frequencies, how it relates to the signals and how much of the error it is, whether or not
// a description (unexplained.h) or a name holds it.
//
// Per channel c of an actuator path (measured: command -> the displacement read, m; force: the
// displacement read -> the load cell's force, N), with target y, the final model's prediction p
// and the residual r = y - p (p of the model the report stands by: the final model without the
// effects the description beat, ActuatorPath::not_named, as unexplained.h describes it):
//   level     RMS of r over the record less kEdgeSeconds at either end / std(y) (sensors.h
//             noise_spread). Not the fit's held-out error alone: an event in the fit's training
//             samples (a rattle for two seconds) does not reach it, yet is in the record and in the
//             response. The ends are left out because a correct model's error gathers there: the
//             force model's zero-phase filters start each pass at rest (signals.h), and the RTHS
//             benchmark's own 15 s record left 88 % of its force residual, 8.8 x its floor, in its
//             last 0.75 s. Everything below is judged on the same samples.
//   floor     the largest of, each / std(y):
//             - the sensor's noise: the white part of r as the sensors were judged (ActuatorPath
//               displacement_noise, force_noise: sensors.h white_noise, which a model error smooth
//               over a sample hardly reaches) or the declared sensor noise, whichever is larger;
//             - the band noise: r's RMS above the model's input band (ChannelSignals input_cutoff,
//               the force channel's: above it the displacement read is its noise, signals.h, so no
//               model fed by it holds what lies there; the RTHS benchmark's clean record leaves
//               its sensor noise, passed through the tracking loop into real force, at 47-81 Hz,
//               0.62 % against a white part of 0.20 %). An event wholly above that band is counted
//               in the floor: the text states the band and its share;
//             - kModelFloor, for a record with no noise at all (rths's own simulated runs), whose
//               correct model still leaves its numerical resolution.
//   above     level > kFloorFactor x floor. Records of the independent simulation with sensor
//             noise and 16-bit converters and a correct model leave 1.0 x (displacement) and
//             1.5 x (force) their floor.
// Where above (ChannelFloor; the numerics are identify/residual/locate.h's):
//   windows   kFloorWindows equal windows, those holding at least kWindowOverUniform /
//             kFloorWindows of the residual's power, merged, the largest first. None: "spread
//             over the record".
//   band      r's spectral peak and the band of the middle 80 % of its power, Hz.
//   relation  the share of r's variance a function of the channel's input x, of its rate v or of
//             the model's output p explains with no form presumed (r's mean in kRelationBins
//             equal-count bins of the signal: the correlation ratio; p is the actuator's motion
//             where the command leads it by the rig's lag; a straight correlation would miss what
//             the fit left orthogonal to its own linear terms, a cubic stroke's residual); the
//             largest is named when at least kMinRelation ("a function of the command explains
//             94 % of it"): a map over a signal holds a dependence on its sign too. Judged over
//             the record and over the samples inside the windows that hold the residual, the
//             stronger kept (a crack's residual follows the displacement after the crack and is
//             noise before it: over the whole record no function of the displacement holds it).
//             With it, r's least-squares line on that signal in the words a lab reads it by (its
//             slope: on the model's output measured / model - 1, on the command a gain, on the
//             displacement read a stiffness N/m, on the command's rate the reading's lead on the
//             model s, on the displacement's rate a damping N s/m), where the line explains at
//             least half of what the map does; else "not in proportion": its sign or size matter.
//             A signal one value of which holds more than a bin's share of the samples (a held
//             reading, a signal at rest) is not tried: its bins would sort r by time, not by it.
//   excess    the share of r's power above the floor: 1 - (floor / level)^2.
//   part      the displacement channel's is "actuator N" (a rod's ripple and a sensor's read
//             alike on it); the force channel's is "specimen N" when r depends on one of those
//             signals (relation), else "load cell N": a force that follows no motion is the
//             reading's (a ripple, a thermal drift, a rattle), not the specimen's.
// Whether above or not (a few spikes need not lift the whole record's RMS):
//   events    identify/residual/events.h on the judged samples, sigma = the floor (in the channel's
//             unit): held readings, spikes, bursts, step changes and capacity drops with their
//             times. Their part: the reading's (the load cell's, the displacement sensor's) where
//             held readings, spikes and step changes hold more of the residual's power than
//             bursts and capacity drops (on the force channel the channel's part above then too:
//             a reading that stood still follows the motion only by not moving with it); else on
//             the force channel the specimen's where they are capacity drops alone or the
//             residual inside them relates to the signals (relation, on their samples), else the
//             channel's part above where above, else the load cell's; on the displacement channel
//             the actuator's. Force events whose largest lies within a held displacement reading
//             are the displacement sensor's (the force model runs on that reading). The re-run
//             models them: the residual inside them put back where the channel reads it (as a
//             description's, unexplained.h), its share of what the re-run leaves stated beside
//             them.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "identify/residual/events.h"
#include "identify/residual/locate.h"
#include "identify/run/actuator_path.h"
#include "identify/run/run_residual.h"
#include "identify/run/unexplained.h"

namespace rths::identify {

inline constexpr double kFloorFactor = 3.0;
inline constexpr double kModelFloor = 1e-3;  // of std(y): a noise-free record's floor
inline constexpr double kEdgeSeconds = 0.25;
inline constexpr double kMinRelation = 0.3;  // of r's variance

// What one channel's residual is against its floor.
struct ChannelFloor {
  int actuator = 0;  // 1-based
  Channel channel = Channel::kMeasured;
  std::string part, channel_word;   // "actuator 1", "displacement"
  double level = 0.0, floor = 0.0;  // RMS of the residual and its floor, of std(y)
  double noise = 0.0;               // of std(y): the record's own noise (white part or declared)
  double band_noise = 0.0;          // of std(y): r above the model's input band
  double band_hz = 0.0;  // the model's input band (Hz, ChannelSignals input_cutoff); 0: none
  bool above = false;    // level > kFloorFactor x floor
  // Where above: when, at what frequencies, how it relates to the signals, how much.
  std::vector<ResidualWindow> windows;  // empty: spread over the record
  double peak_hz = 0.0, band_low_hz = 0.0, band_high_hz = 0.0;
  std::string relation;    // "the rate of the displacement read"; empty: none at kMinRelation
  double explained = 0.0;  // of r's variance, by a function of `relation`
  bool relation_in_windows = false;  // judged on the samples inside `windows`, not the record's
  // The line of r on `relation`'s signal in a lab's words ("as measured / model -30 %", "as a
  // damping of 420 N s/m", "as the reading ahead of the model by -5 ms"); empty where the line
  // holds under half of what the map explains (r follows the signal's sign or size).
  std::string relation_as;
  double excess = 0.0;  // share of the residual's power above the floor
  // Whether above or not: what the residual holds for a moment (events.h), the largest first.
  std::vector<ResidualEvent> events;
  std::string events_part;  // the part the events are on ("load cell 1")
  // The channel's samples (s) and its residual inside the events, 0 elsewhere (unit): what the
  // re-run puts back to model them (event_residuals).
  std::vector<double> time, inside_events;
  std::optional<double> events_share;  // of the re-run's remaining error; absent when not re-run
  bool reported() const { return above || !events.empty(); }
  std::string events_text() const;   // "located in time on load cell 1 (force): spike at ..."
  std::string floor_source() const;  // "the sensor's noise 0.2 %, the residual above ..."
  std::string text() const;
  nlohmann::json json() const;
};

// Each identified channel of `path` against its floor (above). Call after the sensors were
// judged (ActuatorPath noise estimates).
std::vector<ChannelFloor> channel_floors(const ActuatorPath& path);

// "unexplained, every part and channel:" with each description (Unexplained::text), each
// channel above its floor and each channel's events, or " none (every channel at its floor:
// ...)" stating each floor.
std::string unexplained_section(const std::vector<Unexplained>& unexplained,
                                const std::vector<ChannelFloor>& floors);
// Each channel's events as a described residual for the re-run (run_residual.h described): the
// residual inside its events put back where the channel reads it, on its events' part, named
// "<channel> events" ("force events") so that its share is told from a description's.
std::vector<Unexplained> event_residuals(const std::vector<ChannelFloor>& floors);
// Each channel's events' share from the re-run (RunResidual::described).
void set_event_shares(const std::vector<ResidualShare>& described,
                      std::vector<ChannelFloor>& floors);

// The report's `unexplained` list: each description's entry (Unexplained::json), then one entry
// per channel with events: {part, channel, share_pct, kinds ("time_varying", the class of every
// residual located in time, then the events' kinds, once each), when [{kind, start_s, end_s,
// share, size, unit}], text}.
nlohmann::json unexplained_json(const std::vector<Unexplained>& unexplained,
                                const std::vector<ChannelFloor>& floors);

}  // namespace rths::identify
