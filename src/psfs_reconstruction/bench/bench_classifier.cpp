// Pixel classification of one frame set, the DESIGN.md section 6 workload: 8 cameras at
// 320x240 with learned background models, target <= 2 ms on 2 cores. Compared in the same run
// with the plain per-pixel reference (double precision, std::exp, the GMM's own density()),
// which is what a straightforward implementation of the formulas costs.
//
//   bench_classifier [--benchmark_repetitions=5] [--benchmark_min_time=1]
// Time = wall time per 8-image set (real time, so 2 threads are not double-counted);
// counter Mpx_per_s = classified megapixels per second.
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/image_prefilter.h"
#include "psfs_reconstruction/pixel_classifier.h"
#include "../test/synthetic_scene.h"

namespace {

constexpr int kCameras = 8, kW = 320, kH = 240;

psfs::GaussianMixture2D skinModel() {
  // The shipped config/skin_gmm.yaml (UCI-trained), inlined so the benchmark needs no files.
  psfs::GaussianComponent2D a, b;
  a.weight = 0.7297958343;
  a.mean = {0.4271646802, 0.3133250223};
  a.covariance << 0.00052825845, -4.503089752e-05, -4.503089752e-05, 0.0001053800911;
  b.weight = 0.2702041657;
  b.mean = {0.4984218308, 0.3211033892};
  b.covariance << 0.0002877690615, 3.543136088e-05, 3.543136088e-05, 0.0001997317851;
  return psfs::GaussianMixture2D({a, b});
}

// 8 cameras: textured office backgrounds learned from 25 noisy frames, and a frame with a
// person-like foreground (skin blobs, a shirt) and a cast shadow.
struct Rig {
  std::vector<psfs::BackgroundModel> backgrounds;
  std::vector<const psfs::BackgroundModel*> bg_ptrs;
  std::vector<cv::Mat> frames, masks;
  psfs::PixelClassifier classifier{skinModel(), {}, psfs::ClassPriors::fromOccupancy(0.1, 0.01, 8)};
  // The thesis' rg-only model (no intensity term, no gain): what the intensity model costs.
  psfs::PixelClassifier classifier_rg{skinModel(), rgOnly(), psfs::ClassPriors::fromOccupancy(0.1, 0.01, 8)};
  static psfs::PixelClassifierParams rgOnly() {
    psfs::PixelClassifierParams p;
    p.intensity_model = false;
    return p;
  }
  Rig() {
    std::mt19937_64 rng(2024);
    for (int c = 0; c < kCameras; ++c) {
      const cv::Mat office = psfs_test::officeBackground(kW, kH, 100 + c);
      psfs::BackgroundModel m(kW, kH);
      while (!m.ready()) m.addLearningFrame(psfs_test::addNoise(office, 2.0, rng));
      backgrounds.push_back(std::move(m));
      cv::Mat f = office.clone();
      f(cv::Rect(100, 40, 120, 200)).setTo(cv::Scalar(40, 60, 150));  // shirt
      f(cv::Rect(130, 10, 50, 40)).setTo(cv::Scalar(205, 150, 120));  // face
      f(cv::Rect(60, 120, 40, 30)).setTo(cv::Scalar(198, 134, 100));  // hand
      cv::Mat shade = f(cv::Rect(0, 200, 200, 40));
      shade.convertTo(shade, -1, 0.6);  // shadow on the desk
      frames.push_back(psfs_test::addNoise(f, 2.0, rng));
      cv::Mat mask(kH, kW, CV_8UC1, cv::Scalar(0));
      mask(cv::Rect(90, 0, 140, 240)).setTo(255);
      masks.push_back(mask);
    }
    for (const auto& b : backgrounds) bg_ptrs.push_back(&b);
  }
};

Rig& rig() {
  static Rig r;
  return r;
}

void setCounters(benchmark::State& state) {
  const double px = double(kCameras) * kW * kH;
  state.counters["Mpx_per_s"] =
      benchmark::Counter(double(state.iterations()) * px * 1e-6, benchmark::Counter::kIsRate);
}

// The classifier as the pipeline runs it: all 8 images in one OpenMP loop over their rows.
void classify8(benchmark::State& state, const psfs::PixelClassifier& classifier) {
  Rig& r = rig();
  const int threads = int(state.range(0));
  std::vector<cv::Mat> out;
  for (auto _ : state) {
    classifier.classify(r.frames, r.bg_ptrs, out, threads);
    benchmark::DoNotOptimize(out.data());
  }
  setCounters(state);
}
void BM_Classify8(benchmark::State& state) { classify8(state, rig().classifier); }
BENCHMARK(BM_Classify8)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
// Same-run baseline: the thesis' rg-only classifier (PixelClassifierParams::intensity_model off).
void BM_Classify8RgOnly(benchmark::State& state) { classify8(state, rig().classifier_rg); }
BENCHMARK(BM_Classify8RgOnly)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// Baseline: plain per-pixel implementation, double precision, std::exp, no vectorisation,
// one camera after the other on one thread.
void BM_Reference8(benchmark::State& state) {
  Rig& r = rig();
  std::vector<cv::Mat> out(kCameras);
  for (auto _ : state) {
    for (int c = 0; c < kCameras; ++c)
      r.classifier.classifyReference(r.frames[c], r.backgrounds[c], out[c]);
    benchmark::DoNotOptimize(out.data());
  }
  setCounters(state);
}
BENCHMARK(BM_Reference8)->UseRealTime()->Unit(benchmark::kMillisecond);

// Selective background update of all 8 models (not in the 2 ms budget; runs once per frame
// after tracking). Updating every frame with the same image drives the models towards it,
// which does not change the cost.
void BM_BackgroundUpdate8(benchmark::State& state) {
  Rig& r = rig();
  const int threads = int(state.range(0));
  std::vector<psfs::BackgroundModel> models = r.backgrounds;  // keep the rig's models intact
  for (auto _ : state) {
    for (int c = 0; c < kCameras; ++c) models[c].update(r.frames[c], r.masks[c], threads);
    benchmark::ClobberMemory();
  }
  setCounters(state);
}
BENCHMARK(BM_BackgroundUpdate8)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// The noise filter the Reconstructor runs on the 8 images before classifying them
// (image_prefilter.h); BM_Classify8 is the same-run baseline it adds to. Arg: threads.
void prefilter8(benchmark::State& state, psfs::ImagePrefilter type) {
  Rig& r = rig();
  const int threads = int(state.range(0));
  std::vector<cv::Mat> out;
  for (auto _ : state) {
    psfs::prefilterImages(r.frames, psfs::ImagePrefilterParams{type, 3}, &out, threads);
    benchmark::DoNotOptimize(out.data());
  }
  setCounters(state);
}
void BM_PrefilterMedian3(benchmark::State& state) { prefilter8(state, psfs::ImagePrefilter::kMedian); }
BENCHMARK(BM_PrefilterMedian3)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
void BM_PrefilterBox3(benchmark::State& state) { prefilter8(state, psfs::ImagePrefilter::kBox); }
BENCHMARK(BM_PrefilterBox3)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
