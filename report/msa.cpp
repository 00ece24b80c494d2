#include "report/msa.hpp"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>

#include "report/trend.hpp"

namespace springscan::report {

namespace {

using analysis::Expected;
using analysis::fail;

/// One characteristic as one report measured it.
struct Measured {
  std::string unit;
  double value = 0.0;
  double tolerance = 0.0;  ///< T from the report; 0: none
};

using Measurements = std::map<std::string, Measured>;

std::string describe(const v1::InspectionReport& r) {
  std::string text = "seq " + std::to_string(r.result_seq());
  if (!r.created_utc().empty()) text += " (" + r.created_utc() + ")";
  return text;
}

// The trend's own extraction on one report at a time, so that the names match `trend`'s and a
// characteristic the report lacks is simply absent.
Measurements measurements(const v1::InspectionReport& report) {
  Measurements out;
  for (const Characteristic& c : collect_characteristics({report})) {
    double t = 0.0;
    if (c.usl) t = *c.usl - c.lsl.value_or(0.0);
    out[c.name] = Measured{c.unit, c.values.front(), t > 0.0 ? t : 0.0};
  }
  return out;
}

Expected<std::string> single_part_id(const std::vector<v1::InspectionReport>& reports) {
  std::map<std::string, std::size_t> ids;
  for (const auto& r : reports) ++ids[r.input().part_id()];
  if (ids.size() == 1) return ids.begin()->first;
  std::string list;
  for (const auto& [id, count] : ids)
    list += (list.empty() ? "" : ", ") + ("'" + id + "' (" + std::to_string(count) + ")");
  return fail("mixed part ids: " + list + "; a study is of one part, give its reports only");
}

std::vector<Measurements> measure_all(const std::vector<v1::InspectionReport>& reports) {
  std::vector<Measurements> all;
  all.reserve(reports.size());
  for (const auto& r : reports) all.push_back(measurements(r));
  return all;
}

/// Nothing when every name in `names` is measured in every report, else the first that is not.
std::optional<analysis::Error> check_present(const std::vector<v1::InspectionReport>& reports,
                                             const std::vector<Measurements>& all,
                                             const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    std::size_t missing = 0;
    const v1::InspectionReport* first = nullptr;
    for (std::size_t i = 0; i < reports.size(); ++i)
      if (all[i].count(name) == 0 && missing++ == 0) first = &reports[i];
    if (missing == 0) continue;
    if (missing == reports.size()) {
      std::string have;
      for (const auto& [known, m] : all.front()) have += (have.empty() ? "" : ", ") + known;
      return fail("characteristic '" + name + "' is in none of the reports (they have: " + have +
                  ")");
    }
    return fail("characteristic '" + name + "' is missing in " + std::to_string(missing) + " of " +
                std::to_string(reports.size()) + " reports (first: " + describe(*first) +
                "); leave it out with --characteristic, or drop those reports");
  }
  return std::nullopt;
}

double tolerance_of(const std::string& name, const std::vector<Measurements>& all,
                    const MsaSettings& settings) {
  if (const auto it = settings.tolerances.find(name); it != settings.tolerances.end())
    return it->second;
  return all.back().at(name).tolerance;  // the tolerance in force in the newest report
}

std::vector<std::string> every_name(const std::vector<Measurements>& all) {
  std::set<std::string> names;
  for (const auto& m : all)
    for (const auto& [name, value] : m) names.insert(name);
  return {names.begin(), names.end()};
}

Expected<v1::MsaType1Characteristic> type1_characteristic(const std::string& name,
                                                          const std::vector<Measurements>& all,
                                                          double reference,
                                                          const MsaSettings& settings) {
  std::vector<double> values;
  for (const auto& m : all) values.push_back(m.at(name).value);
  const double t = tolerance_of(name, all, settings);
  auto f = type1_figures(values, reference, t);
  if (!f) return f.error().prepend(name + ": ");
  v1::MsaType1Characteristic c;
  c.set_name(name);
  c.set_unit(all.front().at(name).unit);
  c.set_tolerance(t);
  c.set_n(static_cast<int>(f->n));
  c.set_mean(f->mean);
  c.set_stddev(f->stddev);
  c.set_reference(reference);
  c.set_bias(f->bias);
  c.set_bias_t(f->bias_t);
  c.set_bias_p(f->bias_p);
  c.set_bias_significant(f->bias_p < settings.limits.bias_alpha);
  if (f->cg) c.set_cg(*f->cg);
  if (f->cgk) c.set_cgk(*f->cgk);
  c.set_capable(type1_capable(*f, settings.limits));
  *c.mutable_values() = {values.begin(), values.end()};
  return c;
}

/// The reports' indices grouped by part serial, parts in order of first appearance.
Expected<std::vector<std::pair<std::string, std::vector<std::size_t>>>> group_by_serial(
    const std::vector<v1::InspectionReport>& reports, const MsaSettings& settings) {
  std::vector<std::pair<std::string, std::vector<std::size_t>>> parts;
  std::map<std::string, std::size_t> index;
  for (std::size_t i = 0; i < reports.size(); ++i) {
    const std::string& serial = reports[i].input().part_serial();
    if (serial.empty())
      return fail("report " + describe(reports[i]) +
                  " has no input.part_serial (springscan analyze --serial S, or the PLC's "
                  "PART_SERIAL); a type-3 study groups the trials by it");
    const auto [it, added] = index.emplace(serial, parts.size());
    if (added) parts.emplace_back(serial, std::vector<std::size_t>{});
    parts[it->second].second.push_back(i);
  }
  if (parts.size() < settings.min_parts)
    return fail("a type-3 study needs at least " + std::to_string(settings.min_parts) +
                " parts, got " + std::to_string(parts.size()));
  std::string counts;
  bool balanced = true;
  for (const auto& [serial, trials] : parts) {
    balanced = balanced && trials.size() == parts.front().second.size();
    counts += (counts.empty() ? "" : ", ") + serial + ": " + std::to_string(trials.size());
  }
  if (!balanced)
    return fail("unbalanced study: every part needs the same number of trials (" + counts + ")");
  if (parts.front().second.size() < settings.min_trials)
    return fail("a type-3 study needs at least " + std::to_string(settings.min_trials) +
                " trials per part, got " + std::to_string(parts.front().second.size()));
  return parts;
}

Expected<v1::MsaType3Characteristic> type3_characteristic(
    const std::string& name, const std::vector<Measurements>& all,
    const std::vector<std::pair<std::string, std::vector<std::size_t>>>& parts,
    const MsaSettings& settings) {
  std::vector<std::vector<double>> by_part;
  v1::MsaType3Characteristic c;
  for (const auto& [serial, trials] : parts) {
    c.add_part_serials(serial);
    by_part.emplace_back();
    for (const std::size_t i : trials) {
      by_part.back().push_back(all[i].at(name).value);
      c.add_values(by_part.back().back());
    }
  }
  const double t = tolerance_of(name, all, settings);
  auto f = type3_figures(by_part, t);
  if (!f) return f.error().prepend(name + ": ");
  c.set_name(name);
  c.set_unit(all.front().at(name).unit);
  c.set_tolerance(t);
  c.set_parts(static_cast<int>(f->parts));
  c.set_trials(static_cast<int>(f->trials));
  c.set_ev(f->ev);
  c.set_pv(f->pv);
  c.set_grr(f->grr);
  if (f->grr_pct_tolerance) c.set_grr_pct_tolerance(*f->grr_pct_tolerance);
  if (f->grr_pct_total) c.set_grr_pct_total(*f->grr_pct_total);
  if (f->ndc) c.set_ndc(*f->ndc);
  const GrrVerdict verdict = grr_verdict(*f, settings.limits);
  c.set_verdict(to_string(verdict));
  // No ndc (GRR = 0): a gauge without repeat error tells every part apart.
  c.set_ndc_ok(!f->ndc || *f->ndc >= settings.limits.min_ndc);
  c.set_acceptable(verdict == GrrVerdict::kAcceptable && c.ndc_ok());
  return c;
}

}  // namespace

Expected<v1::MsaType1Study> type1_study(const std::vector<v1::InspectionReport>& reports,
                                        const std::map<std::string, double>& references,
                                        const MsaSettings& settings) {
  if (reports.size() < settings.min_type1_reports)
    return fail("a type-1 study needs at least " + std::to_string(settings.min_type1_reports) +
                " reports of the reference part, got " + std::to_string(reports.size()));
  auto part_id = single_part_id(reports);
  if (!part_id) return part_id.error();
  std::vector<std::string> names = settings.only;
  if (names.empty())
    for (const auto& [name, value] : references) names.push_back(name);
  if (names.empty()) return fail("the reference file names no characteristic");
  for (const std::string& name : names)
    if (references.count(name) == 0)
      return fail("characteristic '" + name + "' has no reference value in the reference file");
  const std::vector<Measurements> all = measure_all(reports);
  if (auto missing = check_present(reports, all, names)) return *missing;
  v1::MsaType1Study study;
  study.set_schema("springscan.msa.type1.v1");
  study.set_part_id(*part_id);
  study.set_reports(static_cast<int>(reports.size()));
  bool capable = true;
  for (const std::string& name : names) {
    auto c = type1_characteristic(name, all, references.at(name), settings);
    if (!c) return c.error();
    capable = capable && c->capable();
    *study.add_characteristics() = std::move(*c);
  }
  study.set_capable(capable);
  return study;
}

Expected<v1::MsaType3Study> type3_study(const std::vector<v1::InspectionReport>& reports,
                                        const MsaSettings& settings) {
  auto part_id = single_part_id(reports);
  if (!part_id) return part_id.error();
  auto parts = group_by_serial(reports, settings);
  if (!parts) return parts.error();
  const std::vector<Measurements> all = measure_all(reports);
  const std::vector<std::string> names = settings.only.empty() ? every_name(all) : settings.only;
  if (auto missing = check_present(reports, all, names)) return *missing;
  v1::MsaType3Study study;
  study.set_schema("springscan.msa.type3.v1");
  study.set_part_id(*part_id);
  study.set_reports(static_cast<int>(reports.size()));
  bool acceptable = true;
  for (const std::string& name : names) {
    auto c = type3_characteristic(name, all, *parts, settings);
    if (!c) return c.error();
    acceptable = acceptable && c->acceptable();
    *study.add_characteristics() = std::move(*c);
  }
  study.set_acceptable(acceptable);
  return study;
}

Expected<std::map<std::string, double>> parse_references(std::string_view json) {
  google::protobuf::Struct object;
  const auto status = google::protobuf::util::JsonStringToMessage(std::string(json), &object);
  if (!status.ok()) return fail("not a JSON object: " + status.ToString());
  std::map<std::string, double> out;
  for (const auto& [name, value] : object.fields()) {
    if (value.kind_case() != google::protobuf::Value::kNumberValue)
      return fail("reference '" + name + "' is not a number");
    out[name] = value.number_value();
  }
  return out;
}

Expected<std::pair<std::string, double>> parse_tolerance(const std::string& text) {
  const auto eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0)
    return fail("--tolerance " + text + ": expected NAME=T, e.g. \"bend 1 springback=1.0\"");
  const std::string number = text.substr(eq + 1);
  char* end = nullptr;
  const double t = std::strtod(number.c_str(), &end);
  if (number.empty() || *end != '\0' || !std::isfinite(t) || t <= 0.0)
    return fail("--tolerance " + text + ": T must be a number > 0, got '" + number + "'");
  return std::make_pair(text.substr(0, eq), t);
}

Expected<std::string> msa_to_json(const google::protobuf::Message& study) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(study, &json, options);
  if (!status.ok()) return fail("cannot print the study as JSON: " + status.ToString());
  return json;
}

}  // namespace springscan::report
