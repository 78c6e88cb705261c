#pragma once
// The score summary's fields, described once: each field's key (the `netlab score --json` field
// and the score.h5 /summary name), its unit, the words the text summary gives it, which printers
// print it and how its value is read from a ScoreSummary. The three printers walk this list: the
// text summary (ScoreSummary::BriefReport, through FillSummaryText), the JSON summary (`netlab
// score --json`) and score.h5's /summary group (WriteScore).

#include <Eigen/Core>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "libnetsim/validation/score.h"

namespace netlab::netsim {

enum class SummaryKind {
  kInt,      // a count: JSON integer, score.h5 float64 dataset
  kNumber,   // JSON number (null when not finite), score.h5 float64 dataset
  kText,     // JSON string, score.h5 string attribute of /summary
  kFlag,     // JSON true/false
  kVector3,  // JSON [x, y, z]
  kRows,     // JSON object {row name: rms in mm} (per_class, per_phase)
  kPhases,   // JSON array of the phase rows: name, span, points, rms and its two sigmas, mean d2
  kLines,    // JSON array of strings; in the text, one line each after the label
};

// Where a field is printed (the text summary names the fields it shows by key, FillSummaryText).
inline constexpr unsigned kInJson = 1, kInFile = 2;

struct SummaryValue {
  double number = 0.0;                               // kInt, kNumber, kFlag (0 or 1)
  std::string text;                                  // kText
  Eigen::Vector3d vector = Eigen::Vector3d::Zero();  // kVector3
  std::span<const ScoreRow> rows;                    // kRows, kPhases
  std::span<const std::string> lines;                // kLines
};

struct SummaryField {
  std::string_view key;  // "rms_mm": the JSON key and the score.h5 /summary name
  SummaryKind kind;
  std::string_view unit;   // the value's unit, score.h5's "units" attribute ("mm", "1", "s")
  std::string_view label;  // the field in words, as the text summary names it ("mean d2")
  unsigned outputs;        // kInJson | kInFile
  SummaryValue (*value)(const ScoreSummary&);
};

// Every field, in the JSON summary's order.
std::span<const SummaryField> SummaryFields();

// The field of `key`; throws std::logic_error when there is none.
const SummaryField& FindSummaryField(std::string_view key);

// `text` with each placeholder replaced from `summary` (numbers with 4 significant digits):
//   {key}          the field's value in its unit
//   {key@ms}       a value in s given in ms
//   {key.row}      kRows: the named row's RMS in mm ({per_class.corner})
//   [key]          the field's label, a space, its value ([mean_d2] -> "mean d2 2.93")
// A line holding a kLines field's placeholder is repeated once per line of the field, and left
// out when it has none. An unknown key throws std::logic_error.
std::string FillSummaryText(std::string_view text, const ScoreSummary& summary);

}  // namespace netlab::netsim
