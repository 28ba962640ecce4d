#pragma once
// The method's sources as user-facing text (--help, reports, printed summaries) names them: by
// author and year, as the code comments do.

namespace lidarcal::pipeline::papers {

/// The calibration against fixed landmarks in unknown positions.
inline constexpr const char* kLandmarks = "Alhashimi et al. 2021";
/// The statistical model of triangulation lidars (bias polynomial, noise law, inversion).
inline constexpr const char* kTriangulation = "Alhashimi et al. 2016";
/// Noise estimation by noise consistency.
inline constexpr const char* kNoiseConsistency = "Sharma 2020";

/// Full references, one Markdown list item each.
inline constexpr const char* kReferences =
    "- Alhashimi et al. 2021: A. Alhashimi, M. Magnusson, S. Knorn, D. Varagnolo, \"Calibrating Range Measurements "
    "of Lidars Using Fixed Landmarks in Unknown Positions\", Sensors, 2021.\n"
    "- Alhashimi et al. 2016: A. Alhashimi, D. Varagnolo, T. Gustafsson, \"Statistical Modeling and Calibration of "
    "Triangulation Lidars\", ICINCO 2016.\n"
    "- Sharma 2020: S. V. Sharma, \"In-situ Sensor Calibration Using Noise Consistency\", MSc "
    "thesis, University of Texas at Arlington, 2020.\n";

}  // namespace lidarcal::pipeline::papers
