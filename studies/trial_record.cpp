// SPDX-License-Identifier: BSD-3-Clause
#include "studies/trial_record.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <vector>

namespace lidarcal::studies {
namespace {

/// Appends the fields of a record, comma-separated.
class RecordWriter {
 public:
  void integer(long long v) { next() += std::to_string(v); }
  void flag(bool v) { next() += v ? "1" : "0"; }
  /// Exact: hexadecimal floating point reads back to the same bits ("nan", "inf" for the others).
  void real(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%a", v);
    next() += buf;
  }
  const std::string& text() const { return text_; }

 private:
  std::string& next() {
    if (!text_.empty()) text_ += ',';
    return text_;
  }
  std::string text_;
};

/// Reads the fields of a record in order; every error names the column and what it held.
class RecordReader {
 public:
  explicit RecordReader(const std::string& line) {
    std::size_t start = 0;
    for (;;) {
      const std::size_t comma = line.find(',', start);
      fields_.push_back(
          line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  long long integer(const char* what, long long lo, long long hi) {
    const std::string& f = take(what);
    errno = 0;
    char* end = nullptr;
    const long long v = std::strtoll(f.c_str(), &end, 10);
    if (f.empty() || *end != '\0' || errno != 0 || v < lo || v > hi)
      fail(at_, what,
           "expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi) +
               ", found '" + f + "'");
    return v;
  }
  bool flag(const char* what) { return integer(what, 0, 1) == 1; }
  double real(const char* what) {
    const std::string& f = take(what);
    char* end = nullptr;
    const double v = std::strtod(f.c_str(), &end);
    if (f.empty() || *end != '\0') fail(at_, what, "expected a number, found '" + f + "'");
    return v;
  }
  void finish() const {
    if (at_ != fields_.size())
      throw std::invalid_argument(std::to_string(fields_.size() - at_) +
                                  " column(s) beyond the record's end");
  }

 private:
  const std::string& take(const char* what) {
    if (at_ >= fields_.size()) fail(at_ + 1, what, "the line ends early");
    return fields_[at_++];
  }
  /// `column`: 1-based.
  [[noreturn]] static void fail(std::size_t column, const char* what, const std::string& problem) {
    throw std::invalid_argument("column " + std::to_string(column) + " (" + what + "): " + problem);
  }
  std::vector<std::string> fields_;
  std::size_t at_ = 0;
};

/// More landmarks than any study places (a guard against a damaged count).
constexpr long long kMaxLandmarks = 100000;

void writeEstimator(RecordWriter& w, const EstimatorOutcome& o) {
  w.flag(o.ran);
  w.flag(o.ok);
  for (const RuleOutcome& r : o.rules) {
    w.integer(r.order);
    for (double x : r.mse_ratio) w.real(x);
  }
  w.integer(static_cast<long long>(o.landmarks.size()));
  for (const PositionError& e : o.landmarks) {
    w.real(e.radial_m);
    w.real(e.tangential_m);
  }
}

EstimatorOutcome readEstimator(RecordReader& r) {
  EstimatorOutcome o;
  o.ran = r.flag("ran");
  o.ok = r.flag("ok");
  for (RuleOutcome& rule : o.rules) {
    rule.order = static_cast<int>(r.integer("order", -1, 1000));
    for (double& x : rule.mse_ratio) x = r.real("mse_ratio");
  }
  o.landmarks.resize(static_cast<std::size_t>(r.integer("landmarks", 0, kMaxLandmarks)));
  for (PositionError& e : o.landmarks) {
    e.radial_m = r.real("radial_m");
    e.tangential_m = r.real("tangential_m");
  }
  return o;
}

}  // namespace

std::string trialRecordHeader() {
  return "# cell,trial,detected_landmarks,ceiling[3],{ran,ok,{order,mse_ratio[3]}[2 "
         "rules],landmarks,"
         "{radial_m,tangential_m}[landmarks]}[closed_form,joint,oracle]; reals in C99 hexadecimal "
         "floating point";
}

std::string formatTrialRecord(const TrialRecord& record) {
  RecordWriter w;
  w.integer(static_cast<long long>(record.cell));
  w.integer(static_cast<long long>(record.trial));
  w.integer(record.result.detected_landmarks);
  for (double x : record.result.ceiling) w.real(x);
  for (const EstimatorOutcome& o : record.result.estimators) writeEstimator(w, o);
  return w.text();
}

TrialRecord parseTrialRecord(const std::string& line) {
  RecordReader r(line);
  TrialRecord record;
  constexpr long long kMaxIndex = 1LL << 40;
  record.cell = static_cast<std::size_t>(r.integer("cell", 0, kMaxIndex));
  record.trial = static_cast<std::size_t>(r.integer("trial", 0, kMaxIndex));
  record.result.detected_landmarks =
      static_cast<int>(r.integer("detected_landmarks", 0, kMaxLandmarks));
  for (double& x : record.result.ceiling) x = r.real("ceiling");
  for (EstimatorOutcome& o : record.result.estimators) o = readEstimator(r);
  r.finish();
  return record;
}

}  // namespace lidarcal::studies
