#include "budget.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "text_file.h"

namespace octbake::scene {
namespace {

constexpr const char* kFormat = "octbake-startup-budget";
// A budget is a few hundred bytes; anything near this is not one.
constexpr size_t kMaxBudgetBytes = size_t{1} << 20;
constexpr int kVersion = 1;

// The counters by name, so parsing and listing share one table.
uint64_t* field(StartupCounters& c, const std::string& name) {
  if (name == "files_opened") return &c.files_opened;
  if (name == "bytes_mapped") return &c.bytes_mapped;
  if (name == "levels_decoded") return &c.levels_decoded;
  if (name == "bytes_decompressed") return &c.bytes_decompressed;
  if (name == "heap_allocations") return &c.heap_allocations;
  return nullptr;
}

Error bad(const std::string& label, const std::string& reason) {
  return Error{ErrorCode::corrupt, label + ": " + reason};
}

}  // namespace

StartupCounters counters_from(const LoadStats& stats) {
  StartupCounters c;
  c.files_opened = stats.files_opened;
  c.bytes_mapped = stats.bytes_mapped;
  c.levels_decoded = stats.levels_decoded;
  c.bytes_decompressed = stats.bytes_decompressed;
  return c;
}

std::vector<std::pair<std::string, uint64_t>> counter_list(const StartupCounters& c) {
  return {{"files_opened", c.files_opened},
          {"bytes_mapped", c.bytes_mapped},
          {"levels_decoded", c.levels_decoded},
          {"bytes_decompressed", c.bytes_decompressed},
          {"heap_allocations", c.heap_allocations}};
}

std::string budget_text(const StartupCounters& c) {
  nlohmann::ordered_json j;
  j["format"] = kFormat;
  j["version"] = kVersion;
  nlohmann::ordered_json counters = nlohmann::ordered_json::object();
  for (const auto& [name, value] : counter_list(c)) counters[name] = value;
  j["counters"] = counters;
  return j.dump(2) + "\n";
}

Result<StartupCounters> parse_budget(const std::string& text, const std::string& label) {
  nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return bad(label, "not valid JSON");
  if (!j.is_object()) return bad(label, "not a JSON object");
  for (const auto& [key, value] : j.items())
    if (key != "format" && key != "version" && key != "counters") return bad(label, key + ": unknown key");
  if (!j.contains("format") || j["format"] != kFormat)
    return bad(label, std::string("format: expected \"") + kFormat + "\"");
  if (!j.contains("version") || !j["version"].is_number_integer())
    return bad(label, "version: expected an integer");
  if (j["version"] != kVersion)
    return Error{ErrorCode::unsupported_version, label + ": version " + j["version"].dump() +
                                                     ", this build reads version " + std::to_string(kVersion)};
  if (!j.contains("counters") || !j["counters"].is_object()) return bad(label, "counters: expected an object");
  StartupCounters c;
  const nlohmann::json& counters = j["counters"];
  for (const auto& [key, value] : counters.items()) {
    uint64_t* slot = field(c, key);
    if (!slot) return bad(label, "counters." + key + ": unknown counter");
    if (!value.is_number_unsigned()) return bad(label, "counters." + key + ": expected a non-negative integer");
    *slot = value.get<uint64_t>();
  }
  for (const auto& [name, value] : counter_list(c))
    if (!counters.contains(name)) return bad(label, "counters." + name + ": missing");
  return c;
}

Result<StartupCounters> read_budget(const std::string& path) {
  Result<std::string> text = read_text_file(path, kMaxBudgetBytes);
  if (!text) return text.error();
  return parse_budget(*text, path);
}

Result<bool> write_budget(const std::string& path, const StartupCounters& c) {
  std::ofstream out(path, std::ios::binary);
  out << budget_text(c);
  out.close();
  if (!out) return Error{ErrorCode::io_error, path + ": cannot write"};
  return true;
}

std::vector<std::string> budget_excess(const StartupCounters& measured, const StartupCounters& budget,
                                       const std::string& budget_label) {
  std::vector<std::string> messages;
  const auto got = counter_list(measured), limit = counter_list(budget);
  for (size_t i = 0; i < got.size(); ++i)
    if (got[i].second > limit[i].second)
      messages.push_back("budget exceeded: " + got[i].first + " " + std::to_string(got[i].second) + " > " +
                         std::to_string(limit[i].second) + " (" + budget_label + ")");
  return messages;
}

}  // namespace octbake::scene
