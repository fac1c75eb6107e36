#include "flowsteer/calibration/board.hpp"

#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "number_text.hpp"

namespace flowsteer::calibration {

namespace {

constexpr const char* kFormats =
    "chessboard:COLSxROWS:SQUARE_M (inner corners) or "
    "charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT (squares)";

// A ChArUco view needs this many corners to constrain a pose (and a calibration) reliably.
constexpr int kMinCharucoCorners = 8;
// More corners (or squares) a side than any camera resolves on a printed board; the bound keeps
// the board's corner count and the detector's model of it small.
constexpr int kMaxBoardSide = 100;
// Squares and markers smaller than a printer prints; OpenCV takes lengths as floats, in which
// far smaller ones are 0.
constexpr double kMinLength_m = 1e-4;
// Larger than any board a camera sees whole; the bound keeps the lengths finite as floats.
constexpr double kMaxLength_m = 10.0;

struct Dictionary {
  const char* name;
  cv::aruco::PREDEFINED_DICTIONARY_NAME id;
};

constexpr Dictionary kDictionaries[] = {
    {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
    {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
    {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
    {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
    {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
    {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
    {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
    {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
    {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
    {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
    {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
    {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
    {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
    {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
    {"DICT_7X7_250", cv::aruco::DICT_7X7_250},
    {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
    {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
    {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5},
    {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9},
    {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10},
    {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11},
};

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, separator)) {
    parts.push_back(part);
  }
  if (!text.empty() && text.back() == separator) {
    parts.emplace_back();
  }
  return parts;
}

// The dictionary named `name`; nullptr for a name OpenCV does not know.
const Dictionary* find_dictionary(const std::string& name) {
  for (const Dictionary& d : kDictionaries) {
    if (name == d.name) {
      return &d;
    }
  }
  return nullptr;
}

[[noreturn]] void bad(const std::string& text, const std::string& why) {
  throw std::invalid_argument("board '" + text + "': " + why + " (expected " + kFormats + ")");
}

int whole(const std::string& text, const std::string& part, const char* what, int minimum,
          int maximum) {
  int value = 0;
  const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), value);
  if (error != std::errc() || end != part.data() + part.size()) {
    bad(text, std::string(what) + " '" + part + "' is not a whole number");
  }
  if (value < minimum) {
    bad(text, std::string(what) + " must be at least " + std::to_string(minimum) + ", got " + part);
  }
  if (value > maximum) {
    bad(text, std::string(what) + " must be at most " + std::to_string(maximum) + ", got " + part);
  }
  return value;
}

double length(const std::string& text, const std::string& part, const char* what) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), value);
  if (error != std::errc() || end != part.data() + part.size() || !std::isfinite(value)) {
    bad(text, std::string(what) + " '" + part + "' is not a number");
  }
  if (!(value > 0.0)) {
    bad(text, std::string(what) + " must be positive, got " + part);
  }
  if (value < kMinLength_m) {
    bad(text, std::string(what) + " must be at least 0.0001 m, got " + part);
  }
  if (value > kMaxLength_m) {
    bad(text, std::string(what) + " must be at most 10 m, got " + part);
  }
  return value;
}

}  // namespace

BoardSpec BoardSpec::parse(const std::string& text) {
  const std::vector<std::string> parts = split(text, ':');
  BoardSpec spec;
  if (parts.empty() || (parts[0] != "chessboard" && parts[0] != "charuco")) {
    bad(text, std::string("unknown board type '") + (parts.empty() ? "" : parts[0].c_str()) + "'");
  }
  spec.kind = parts[0] == "chessboard" ? Kind::chessboard : Kind::charuco;
  const std::size_t expected = spec.kind == Kind::chessboard ? 3 : 5;
  if (parts.size() != expected) {
    bad(text, parts[0] + " takes " + std::to_string(expected - 1) + " fields after the type, got " +
                  std::to_string(parts.size() - 1));
  }
  const std::vector<std::string> size = split(parts[1], 'x');
  if (size.size() != 2) {
    bad(text, "size '" + parts[1] + "' is not COLSxROWS");
  }
  // A chessboard needs 2 inner corners each way to tell rows from columns; a ChArUco board
  // needs 2 squares each way to have an inner corner at all.
  spec.cols = whole(text, size[0], "COLS", 2, kMaxBoardSide);
  spec.rows = whole(text, size[1], "ROWS", 2, kMaxBoardSide);
  spec.square_m = length(text, parts[2], "SQUARE_M");
  if (spec.kind == Kind::charuco) {
    spec.marker_m = length(text, parts[3], "MARKER_M");
    // Compared as the floats OpenCV's board is made of: 0.10000000001 is not smaller than 0.1.
    if (static_cast<float>(spec.marker_m) >= static_cast<float>(spec.square_m)) {
      bad(text, "MARKER_M (" + parts[3] + ") must be smaller than SQUARE_M (" + parts[2] + ")");
    }
    spec.dictionary = parts[4];
    if (find_dictionary(spec.dictionary) == nullptr) {
      std::string names;
      for (const Dictionary& d : kDictionaries) {
        names += names.empty() ? d.name : std::string(", ") + d.name;
      }
      bad(text, "unknown dictionary '" + spec.dictionary + "' (known: " + names + ")");
    }
  }
  return spec;
}

std::string BoardSpec::text() const {
  std::string t = kind == Kind::chessboard ? "chessboard:" : "charuco:";
  t += std::to_string(cols) + "x" + std::to_string(rows) + ":" + number_text(square_m);
  if (kind == Kind::charuco) {
    t += ':' + number_text(marker_m) + ':' + dictionary;
  }
  return t;
}

std::vector<std::string> BoardSpec::warnings() const {
  std::vector<std::string> w;
  if (kind == Kind::charuco && rows % 2 == 0) {
    w.push_back("board " + text() + ": a ChArUco board with an even number of rows (" +
                std::to_string(rows) +
                ") is laid out by OpenCV 4.6 (the version built in) differently from OpenCV "
                "before 4.6 and from most printed and bought boards (OpenCV 4.7+ calls that the "
                "legacy pattern): such a board will not be found. Print the board with OpenCV 4.6 "
                "or use one with an odd number of rows");
  }
  return w;
}

int BoardSpec::corner_count() const {
  return kind == Kind::chessboard ? cols * rows : (cols - 1) * (rows - 1);
}

BoardDetector::BoardDetector(BoardSpec spec) : spec_(std::move(spec)) {
  if (spec_.kind == BoardSpec::Kind::chessboard) {
    for (int r = 0; r < spec_.rows; ++r) {
      for (int c = 0; c < spec_.cols; ++c) {
        chessboard_points_.emplace_back(static_cast<float>(c * spec_.square_m),
                                        static_cast<float>(r * spec_.square_m), 0.0F);
      }
    }
    return;
  }
  const Dictionary* dictionary = find_dictionary(spec_.dictionary);
  if (dictionary == nullptr) {
    throw std::invalid_argument("board " + spec_.text() + ": unknown dictionary");
  }
  // Checked before the board is made: OpenCV makes one marker per white square whether or not
  // the dictionary has that many.
  const cv::Ptr<cv::aruco::Dictionary> markers_dictionary =
      cv::aruco::getPredefinedDictionary(dictionary->id);
  const int markers = spec_.cols * spec_.rows / 2;
  if (markers_dictionary->bytesList.rows < markers) {
    throw std::invalid_argument("board " + spec_.text() + ": needs " + std::to_string(markers) +
                                " markers, " + spec_.dictionary + " has only " +
                                std::to_string(markers_dictionary->bytesList.rows));
  }
  charuco_ =
      cv::aruco::CharucoBoard::create(spec_.cols, spec_.rows, static_cast<float>(spec_.square_m),
                                      static_cast<float>(spec_.marker_m), markers_dictionary);
}

BoardDetector::~BoardDetector() = default;

std::optional<BoardView> BoardDetector::detect(const cv::Mat& image, std::string& why) const {
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  BoardView view;
  if (spec_.kind == BoardSpec::Kind::chessboard) {
    const cv::Size pattern(spec_.cols, spec_.rows);
    if (!cv::findChessboardCorners(grey, pattern, view.image_points,
                                   cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
      why = std::string("no ") + std::to_string(spec_.cols) + "x" + std::to_string(spec_.rows) +
            " chessboard found (it must be seen whole, with its white border)";
      return std::nullopt;
    }
    cv::cornerSubPix(grey, view.image_points, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-3));
    view.object_points = chessboard_points_;
    return view;
  }
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::aruco::detectMarkers(grey, charuco_->dictionary, marker_corners, marker_ids);
  if (marker_ids.empty()) {
    why = "no " + spec_.dictionary + " marker found";
    return std::nullopt;
  }
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, grey, charuco_, corners, ids);
  if (static_cast<int>(ids.size()) < kMinCharucoCorners) {
    why = std::to_string(marker_ids.size()) + " markers but only " + std::to_string(ids.size()) +
          " ChArUco corners found (at least " + std::to_string(kMinCharucoCorners) + " needed)" +
          (spec_.rows % 2 == 0 ? "; an even row count may mean a board of the pre-4.6 layout" : "");
    return std::nullopt;
  }
  view.image_points = corners;
  for (const int id : ids) {
    view.object_points.push_back(charuco_->chessboardCorners[static_cast<std::size_t>(id)]);
  }
  return view;
}

}  // namespace flowsteer::calibration
