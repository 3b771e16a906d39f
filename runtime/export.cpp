#include "runtime/export.h"

#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace rths::runtime {
namespace {

void put(std::ofstream& out, double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, ",%.17g", x);
  out << buffer;
}

}  // namespace

std::size_t write_csv(const RecordContents& record, const std::filesystem::path& csv) {
  const RunHeader* header = record.header();
  if (!header) throw std::invalid_argument("the run record has no header entry");
  std::ofstream out(csv);
  if (!out) throw std::runtime_error("cannot write " + csv.string());
  out << "step,time,ground_acceleration";
  for (const char* name : {"u", "v", "a"})
    for (int i = 1; i <= header->dofs(); ++i) out << "," << name << i;
  for (const char* name : {"command", "realised", "force"})
    for (int j = 1; j <= header->actuators(); ++j) out << "," << name << j;
  for (int id : header->link_node_ids())
    for (const char* name :
         {"answered_step", "injected_lag", "round_trip", "one_way_down", "one_way_up"})
      out << ",node" << id << "_" << name;
  out << ",lateness,overrun\n";
  std::size_t rows = 0;
  for (const StepRecord* s : record.steps()) {
    out << s->step();
    put(out, s->time());
    put(out, s->ground_acceleration());
    for (const auto* field : {&s->displacement(), &s->velocity(), &s->acceleration()})
      for (int i = 0; i < header->dofs(); ++i) put(out, i < field->size() ? field->Get(i) : 0.0);
    for (const auto* field : {&s->command(), &s->realised(), &s->measured_force()})
      for (int j = 0; j < header->actuators(); ++j)
        put(out, j < field->size() ? field->Get(j) : 0.0);
    for (int l = 0; l < header->link_node_ids_size(); ++l) {
      // Step 0 has no exchange: its link columns are empty.
      if (l >= s->links_size()) {
        out << ",,,,,";
        continue;
      }
      const LinkSample& link = s->links(l);
      out << "," << link.answered_step();
      put(out, link.injected_lag());
      put(out, link.round_trip());
      put(out, link.one_way_down());
      put(out, link.one_way_up());
    }
    put(out, s->lateness());
    out << "," << (s->overrun() ? 1 : 0) << "\n";
    ++rows;
  }
  if (!out) throw std::runtime_error("error writing " + csv.string());
  return rows;
}

}  // namespace rths::runtime
