#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace cv::aruco {
class CharucoBoard;
}

namespace flowsteer::calibration {

// A calibration target.
//   chessboard:COLSxROWS:SQUARE_M                 COLS x ROWS inner corners, squares SQUARE_M wide
//   charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT      COLS x ROWS squares, markers of OpenCV's
//                                                 predefined dictionary DICT (e.g. DICT_4X4_50)
// COLS and ROWS are at most 100.
// The board frame: origin at the first corner, x along a row, y along a column, z = x × y,
// which points into the board when it is seen from its printed side.
struct BoardSpec {
  enum class Kind { chessboard, charuco };
  Kind kind = Kind::chessboard;
  int cols = 0;
  int rows = 0;
  double square_m = 0.0;
  double marker_m = 0.0;   // charuco only
  std::string dictionary;  // charuco only

  // Throws std::invalid_argument saying which part of `text` is wrong and what is expected.
  static BoardSpec parse(const std::string& text);
  std::string text() const;
  // What the user should know before trusting a detection: OpenCV 4.6 lays out ChArUco boards
  // with an even number of rows differently from earlier versions and from most printed boards.
  std::vector<std::string> warnings() const;
  // The corners a full view of the board shows.
  int corner_count() const;
};

// The board corners found in one image, with where they are on the board.
struct BoardView {
  std::vector<cv::Point2f> image_points;   // pixels, refined to sub-pixel accuracy
  std::vector<cv::Point3f> object_points;  // metres, board frame, z = 0
};

class BoardDetector {
 public:
  // Throws std::invalid_argument for an unknown ChArUco dictionary or a board it cannot hold.
  explicit BoardDetector(BoardSpec spec);
  ~BoardDetector();
  BoardDetector(const BoardDetector&) = delete;
  BoardDetector& operator=(const BoardDetector&) = delete;

  // The corners of the board in a BGR or grey image; nullopt, with the reason in `why`, when
  // the board is not there or too little of it is seen. Chessboards must be seen whole
  // (cv::findChessboardCorners, then cv::cornerSubPix); ChArUco boards may be partly hidden
  // (cv::aruco::detectMarkers, cv::aruco::interpolateCornersCharuco).
  std::optional<BoardView> detect(const cv::Mat& image, std::string& why) const;

  const BoardSpec& spec() const { return spec_; }

 private:
  BoardSpec spec_;
  std::vector<cv::Point3f> chessboard_points_;
  cv::Ptr<cv::aruco::CharucoBoard> charuco_;
};

}  // namespace flowsteer::calibration
