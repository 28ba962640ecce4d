// SPDX-License-Identifier: BSD-3-Clause
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

/// The simultaneous calibration of odometry and the laser's mounting (`lidarcal odometry`).
inline constexpr const char* kOdometry = "Censi et al. 2013";

/// The model discrepancy beside a fitted model (calibration/discrepancy.hpp).
inline constexpr const char* kDiscrepancy = "Kennedy & O'Hagan 2001";
/// Its variance by restricted maximum likelihood over the measured entries.
inline constexpr const char* kReml = "Viechtbauer 2005";
/// Prediction intervals with an estimated between-unit variance: Student t.
inline constexpr const char* kPredictionInterval = "Higgins, Thompson & Spiegelhalter 2009";

/// Full references, one Markdown list item each.
inline constexpr const char* kReferences =
    "- Alhashimi et al. 2021: A. Alhashimi, M. Magnusson, S. Knorn, D. Varagnolo, \"Calibrating "
    "Range Measurements "
    "of Lidars Using Fixed Landmarks in Unknown Positions\", Sensors, 2021.\n"
    "- Alhashimi et al. 2016: A. Alhashimi, D. Varagnolo, T. Gustafsson, \"Statistical Modeling "
    "and Calibration of "
    "Triangulation Lidars\", ICINCO 2016.\n"
    "- Sharma 2020: S. V. Sharma, \"In-situ Sensor Calibration Using Noise Consistency\", MSc "
    "thesis, University of Texas at Arlington, 2020.\n"
    "- Kennedy & O'Hagan 2001: M. C. Kennedy, A. O'Hagan, \"Bayesian calibration of computer "
    "models\", Journal of "
    "the Royal Statistical Society B 63(3), 2001.\n"
    "- Viechtbauer 2005: W. Viechtbauer, \"Bias and efficiency of meta-analytic variance "
    "estimators in the "
    "random-effects model\", Journal of Educational and Behavioral Statistics 30(3), 2005.\n"
    "- Higgins, Thompson & Spiegelhalter 2009: J. P. T. Higgins, S. G. Thompson, D. J. "
    "Spiegelhalter, \"A "
    "re-evaluation of random-effects meta-analysis\", Journal of the Royal Statistical Society A "
    "172(1), 2009.\n";

}  // namespace lidarcal::pipeline::papers
