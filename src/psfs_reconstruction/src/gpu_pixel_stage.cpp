#include "psfs_reconstruction/gpu_pixel_stage.h"

#include <cstddef>
#include <cstring>
#include <stdexcept>

#include "psfs_reconstruction/cuda_device.h"
#include "psfs_reconstruction/image_checks.h"
#include "psfs_reconstruction/view_evidence.h"
#include "pixel_pipeline_device.h"
#include "pixel_stage_host.h"

namespace psfs {
namespace {

std::string camName(std::size_t c) { return "cam" + std::to_string(c); }

// Copies an image's rows into a contiguous (pinned) buffer.
void stage(const cv::Mat& image, std::uint8_t* dst) {
  const std::size_t row = std::size_t(image.cols) * image.elemSize();
  if (image.isContinuous()) {
    std::memcpy(dst, image.data, row * image.rows);
    return;
  }
  for (int y = 0; y < image.rows; ++y) std::memcpy(dst + row * y, image.ptr(y), row);
}

// The address of a member of a device-side struct, without dereferencing the pointer.
template <typename T>
const float* gainOf(const T* peak) {
  return reinterpret_cast<const float*>(reinterpret_cast<const char*>(peak) +
                                        offsetof(pixel::GainPeak, gain));
}

}  // namespace

struct GpuPixelStage::Impl {
  explicit Impl(PixelClassifier c) : classifier(std::move(c)) {}
  PixelClassifier classifier;
  std::vector<detail::SkinKernelTerm> skin_terms;
  std::string reason;
  std::unique_ptr<detail::PixelPipelineDevice> device;
  std::vector<detail::ImageSize> sizes;
  std::vector<BackgroundModelParams> background_params;
  std::vector<bool> classified;  // camera had an image in the last classified frame
  bool frame = false;            // a frame was classified since the upload
  GpuEvidence body, skin;

  detail::PixelPipelineDevice& dev() const {
    if (!device) throw std::runtime_error("GpuPixelStage: " + reason);
    return *device;
  }
  void needCameras(const char* what) const {
    dev();
    if (sizes.empty())
      throw std::logic_error(std::string("GpuPixelStage::") + what +
                             ": no background models uploaded yet");
  }
};

GpuPixelStage::GpuPixelStage(const GaussianMixture2D& skin, const PixelClassifierParams& params,
                             const ClassPriors& priors)
    : impl_(std::make_unique<Impl>(PixelClassifier(skin, params, priors))) {
  impl_->skin_terms = skinKernelTerms(skin);
  if (impl_->skin_terms.size() > std::size_t(pixel::kMaxSkinTerms))
    throw std::invalid_argument("GpuPixelStage: the skin model has " +
                                std::to_string(impl_->skin_terms.size()) +
                                " components, at most " + std::to_string(pixel::kMaxSkinTerms) +
                                " fit the kernel's arguments");
  const cuda::DeviceInfo& d = cuda::device();
  if (!d.usable) {
    impl_->reason = d.describe();
    return;
  }
  try {
    impl_->device = detail::makePixelPipelineDevice();
    if (!impl_->device) impl_->reason = "this build has no CUDA pixel stage";
  } catch (const std::runtime_error& e) {
    impl_->reason = e.what();
  }
}

GpuPixelStage::~GpuPixelStage() = default;
GpuPixelStage::GpuPixelStage(GpuPixelStage&&) noexcept = default;
GpuPixelStage& GpuPixelStage::operator=(GpuPixelStage&&) noexcept = default;

bool GpuPixelStage::usable() const { return impl_->device != nullptr; }
const std::string& GpuPixelStage::reason() const { return impl_->reason; }
const PixelClassifier& GpuPixelStage::classifier() const { return impl_->classifier; }
void GpuPixelStage::setParams(const PixelClassifierParams& params) {
  impl_->classifier.setParams(params);
}
void GpuPixelStage::setPriors(const ClassPriors& priors) { impl_->classifier.setPriors(priors); }
void GpuPixelStage::setClothingColour(const ColourGaussian* colour, double weight) {
  impl_->classifier.setClothingColour(colour, weight);
}
int GpuPixelStage::cameras() const { return int(impl_->sizes.size()); }
std::size_t GpuPixelStage::deviceAllocations() const {
  return impl_->device ? impl_->device->allocations() : 0;
}

void GpuPixelStage::uploadBackgrounds(const std::vector<const BackgroundModel*>& models) {
  Impl& m = *impl_;
  detail::PixelPipelineDevice& dev = m.dev();
  if (models.empty()) throw std::invalid_argument("GpuPixelStage: no background models");
  std::vector<detail::ImageSize> sizes;
  for (std::size_t c = 0; c < models.size(); ++c) {
    if (!models[c]) throw std::invalid_argument(camName(c) + ": no background model");
    if (!models[c]->ready())
      throw std::invalid_argument(camName(c) + ": background model not learned yet");
    sizes.push_back({models[c]->width(), models[c]->height()});
  }
  m.frame = false;
  m.body.clear();
  m.skin.clear();
  m.sizes.clear();  // until the upload succeeded
  dev.resize(sizes);
  m.background_params.clear();
  for (std::size_t c = 0; c < models.size(); ++c) {
    dev.uploadPlanes(int(c), models[c]->planes());
    m.background_params.push_back(models[c]->params());
  }
  m.sizes = sizes;
  m.classified.assign(sizes.size(), false);
}

void GpuPixelStage::downloadBackgrounds(const std::vector<BackgroundModel*>& models) const {
  const Impl& m = *impl_;
  m.needCameras("downloadBackgrounds");
  if (models.size() != m.sizes.size())
    throw std::invalid_argument("GpuPixelStage: " + std::to_string(models.size()) +
                                " models for " + std::to_string(m.sizes.size()) + " cameras");
  for (std::size_t c = 0; c < models.size(); ++c) {
    if (!models[c] || !models[c]->ready() || models[c]->width() != m.sizes[c].width ||
        models[c]->height() != m.sizes[c].height)
      throw std::invalid_argument(camName(c) +
                                  ": need a learned background model of the uploaded size");
    m.dev().downloadPlanes(int(c), models[c]->mutablePlanes());
  }
}

std::vector<ClassificationStats> GpuPixelStage::classify(const std::vector<cv::Mat>& rgb,
                                                         std::vector<cv::Mat>* likelihoods) {
  Impl& m = *impl_;
  m.needCameras("classify");
  detail::PixelPipelineDevice& dev = m.dev();
  const std::size_t n = m.sizes.size();
  if (rgb.size() != n)
    throw std::invalid_argument("GpuPixelStage: " + std::to_string(rgb.size()) +
                                " images for " + std::to_string(n) + " cameras");
  for (std::size_t c = 0; c < n; ++c)
    if (!rgb[c].empty()) checkRgb8(rgb[c], m.sizes[c].width, m.sizes[c].height, camName(c));

  const PixelClassifierParams& params = m.classifier.params();
  const ClassifierKernelConstants kc = kernelConstants(m.classifier);
  const pixel::PixelConstants& k = kc.k;
  const bool compensate = gainCompensated(params);
  const pixel::GainConstants gc = gainConstants(params);
  m.frame = true;
  m.body.clear();
  m.skin.clear();
  for (std::size_t c = 0; c < n; ++c) {
    m.classified[c] = !rgb[c].empty();
    const detail::PixelCameraBuffers& b = dev.buffers(int(c));
    if (rgb[c].empty()) {
      dev.clearLikelihood(int(c));
      continue;
    }
    // Staging this camera overlaps the device's work on the previous ones.
    stage(rgb[c], b.host_rgb);
    const BackgroundPlanes planes = readOnly(b.background);
    const pixel::ClassifyArgs args =
        classifyArgs(k, m.skin_terms, kc.clothingTerm(), b.rgb, planes, b.likelihood, b.width,
                     b.height,
                     compensate ? gainOf(b.gain_peak) : nullptr);
    const pixel::GainArgs gain = gainArgs(gc, b.rgb, planes, b.width, b.height);
    dev.classify(int(c), args, compensate ? &gain : nullptr, likelihoods != nullptr);
  }
  dev.synchronize();

  std::vector<ClassificationStats> stats(n);
  if (likelihoods) likelihoods->resize(n);
  for (std::size_t c = 0; c < n; ++c) {
    const detail::PixelCameraBuffers& b = dev.buffers(int(c));
    if (likelihoods) {
      cv::Mat& out = (*likelihoods)[c];
      out.create(b.height, b.width, CV_8UC2);
      if (!m.classified[c]) {
        out.setTo(0);
      } else {
        const std::size_t row = std::size_t(b.width) * 2;
        for (int y = 0; y < b.height; ++y)
          std::memcpy(out.ptr(y), b.host_likelihood + row * y, row);
      }
    }
    if (m.classified[c])
      stats[c] = classificationStats(*b.host_totals, b.width * b.height,
                                     compensate ? b.host_gain_peak : nullptr);
  }
  return stats;
}

void GpuPixelStage::buildEvidence(const std::vector<cv::Mat>& active, bool body_bilinear,
                                  bool skin_bilinear, bool with_skin) {
  Impl& m = *impl_;
  m.needCameras("buildEvidence");
  if (!m.frame) throw std::logic_error("GpuPixelStage::buildEvidence: no frame classified yet");
  detail::PixelPipelineDevice& dev = m.dev();
  const std::size_t n = m.sizes.size();
  if (!active.empty() && active.size() != n)
    throw std::invalid_argument("GpuPixelStage: " + std::to_string(active.size()) +
                                " active masks for " + std::to_string(n) + " cameras");
  for (std::size_t c = 0; c < active.size(); ++c)
    if (!active[c].empty() &&
        (active[c].type() != CV_8UC1 || active[c].cols != m.sizes[c].width ||
         active[c].rows != m.sizes[c].height))
      throw std::invalid_argument(camName(c) +
                                  ": active mask must be CV_8UC1 of the likelihood image's size");
  const int classes = with_skin ? 2 : 1;
  const bool bilinear[2] = {body_bilinear, skin_bilinear};
  GpuEvidence* out[2] = {&m.body, &m.skin};
  m.body.assign(n, GpuViewEvidence());
  m.skin.assign(with_skin ? n : 0, GpuViewEvidence());
  for (std::size_t c = 0; c < n; ++c) {
    const detail::PixelCameraBuffers& b = dev.buffers(int(c));
    std::size_t inactive = 0;
    const cv::Mat none;
    const cv::Mat& mask = active.empty() ? none : active[c];
    const pixel::ActiveMode mode = activeMode(mask, &inactive);
    const bool upload = mode == pixel::ActiveMode::kMask;
    if (upload) stage(mask, b.host_mask);
    for (int cls = 0; cls < classes; ++cls) {
      const pixel::EvidenceArgs args =
          evidenceArgs(b.likelihood, 2, cls, mode, b.mask, b.width, b.height, b.terms[cls],
                       b.pairs[cls]);
      dev.evidence(int(c), args, upload && cls == 0, bilinear[cls]);
      GpuViewEvidence& e = (*out[cls])[c];
      e.terms = b.terms[cls];
      e.pairs = bilinear[cls] ? b.pairs[cls] : nullptr;
      e.width = b.width;
      e.height = b.height;
      e.quad_stride = b.width + 2 * ViewEvidence::kQuadPad;
      e.has_inactive_pixels = inactive > 0;
    }
  }
  dev.synchronize();
}

const GpuEvidence& GpuPixelStage::bodyEvidence() const { return impl_->body; }
const GpuEvidence& GpuPixelStage::skinEvidence() const { return impl_->skin; }

void GpuPixelStage::readEvidence(int camera, bool skin, std::vector<std::int16_t>* terms,
                                 std::vector<std::uint16_t>* pairs) const {
  const Impl& m = *impl_;
  const GpuEvidence& ev = skin ? m.skin : m.body;
  if (camera < 0 || std::size_t(camera) >= ev.size())
    throw std::out_of_range("GpuPixelStage::readEvidence: no such view (build the evidence first)");
  const GpuViewEvidence& e = ev[camera];
  pixel::EvidenceArgs shape;
  shape.width = e.width;
  shape.height = e.height;
  terms->resize(std::size_t(shape.pixels()) + pixel::kTermGuard);
  m.dev().copyToHost(terms->data(), e.terms, terms->size() * sizeof(std::int16_t));
  pairs->clear();
  if (!e.pairs) return;
  pairs->resize(std::size_t(shape.pairCount()));
  m.dev().copyToHost(pairs->data(), e.pairs, pairs->size() * sizeof(std::uint16_t));
}

void GpuPixelStage::updateBackground(const std::vector<cv::Mat>& masks,
                                     const std::vector<bool>& update) {
  Impl& m = *impl_;
  m.needCameras("updateBackground");
  detail::PixelPipelineDevice& dev = m.dev();
  const std::size_t n = m.sizes.size();
  if (!masks.empty() && masks.size() != n)
    throw std::invalid_argument("GpuPixelStage: " + std::to_string(masks.size()) +
                                " masks for " + std::to_string(n) + " cameras");
  if (!update.empty() && update.size() != n)
    throw std::invalid_argument("GpuPixelStage: " + std::to_string(update.size()) +
                                " update flags for " + std::to_string(n) + " cameras");
  // Everything is checked before any camera is updated.
  std::vector<bool> want(n);
  for (std::size_t c = 0; c < n; ++c) {
    want[c] = update.empty() ? m.classified[c] : bool(update[c]);
    if (want[c] && !m.classified[c])
      throw std::logic_error("GpuPixelStage::updateBackground: " + camName(c) +
                             " had no image in the last classified frame");
    if (want[c] && !masks.empty() && !masks[c].empty())
      checkMask(masks[c], m.sizes[c].width, m.sizes[c].height, camName(c));
  }
  for (std::size_t c = 0; c < n; ++c) {
    if (!want[c]) continue;
    const detail::PixelCameraBuffers& b = dev.buffers(int(c));
    const bool has_mask = !masks.empty() && !masks[c].empty();
    if (has_mask) stage(masks[c], b.host_mask);
    dev.update(int(c), updateArgs(m.background_params[c], b.rgb, has_mask ? b.mask : nullptr,
                                  b.background, b.width * b.height),
               has_mask);
  }
  dev.synchronize();
}

}  // namespace psfs
