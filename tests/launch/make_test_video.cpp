// Writes a short recording for the command-line tests of `flowsteer run` and `flowsteer
// replay`: a camera moving towards a textured wall (an expanding view, so that the flow has
// something to find), as OUT_DIR/run.mp4 at 10 frames per second.
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_test_video OUT_DIR\n";
    return EXIT_FAILURE;
  }
  const std::filesystem::path dir(argv[1]);
  std::filesystem::create_directories(dir);
  const cv::Size size(160, 120);
  cv::Mat texture(480, 640, CV_8UC3);
  cv::theRNG().state = 7;
  cv::randu(texture, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::GaussianBlur(texture, texture, {0, 0}, 2.0);
  const std::string path = (dir / "run.mp4").string();
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 10.0, size);
  if (!writer.isOpened()) {
    std::cerr << "make_test_video: cannot write " << path << "\n";
    return EXIT_FAILURE;
  }
  cv::Mat frame;
  for (int i = 0; i < 12; ++i) {
    // Each frame shows a 4 % smaller part of the wall: the camera closes in.
    const double scale = std::pow(0.96, i);
    const cv::Size crop(static_cast<int>(480 * scale), static_cast<int>(360 * scale));
    const cv::Rect window((640 - crop.width) / 2, (480 - crop.height) / 2, crop.width, crop.height);
    cv::resize(texture(window), frame, size, 0.0, 0.0, cv::INTER_AREA);
    writer.write(frame);
  }
  return EXIT_SUCCESS;
}
