// Trains the skin-colour GMM p(c|S) in normalised rg (thesis 4.2.1) from labelled pixels,
// reports the ROC AUC on a seeded held-back split and writes the model YAML.
//
//   train_skin_model --data Skin_NonSkin.txt [--data more.csv --order rgb ...]
//                    [--out skin_gmm.yaml] [--components 2] [--holdout 0.2]
//                    [--split-seed 20080101] [--em-seed 12345] [--nonskin-components 4]
//                    [--note "data source / licence"]
//
// The score that matters is p(c|S) itself: the pipeline's P(S|c) compares it with a uniform
// non-skin density, so it is a monotonic function of p(c|S) and has the same AUC. The
// optional non-skin GMM gives the likelihood-ratio AUC for comparison only (not shipped).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "psfs_reconstruction/color_space.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/labelled_pixels.h"
#include "tabletop_common/cli_args.h"

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: train_skin_model --data FILE [--data FILE ...] [options]\n"
               "  --data FILE            labelled pixels; format set by the --order before it\n"
               "  --order bgr|rgb        column order of the following --data files: bgr = UCI\n"
               "                         Skin_NonSkin.txt (B,G,R,label), rgb = R,G,B,label\n"
               "                         (default bgr)\n"
               "  --skin-label N         label value meaning skin (default 1)\n"
               "  --out FILE             model YAML to write (default: none)\n"
               "  --components K         skin GMM components (default 2, as in the thesis)\n"
               "  --holdout F            held-back fraction for the AUC (default 0.2)\n"
               "  --split-seed S         seed of the hold-out split (default %llu)\n"
               "  --em-seed S            seed of the EM initialisation (default 12345)\n"
               "  --nonskin-components K also fit a K-component non-skin GMM and report the\n"
               "                         likelihood-ratio AUC (default 0 = off)\n"
               "  --note TEXT            extra comment line(s) for the YAML header\n",
               (unsigned long long)psfs::kDefaultSplitSeed);
}

std::vector<double> skinScores(const psfs::GaussianMixture2D& skin,
                               const psfs::GaussianMixture2D* nonskin,
                               const psfs::LabelledPixels& data) {
  std::vector<double> s(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto c = psfs::toNormalizedRgI(data.rgb[i][0], data.rgb[i][1], data.rgb[i][2]);
    s[i] = skin.logDensity(c.r, c.g) - (nonskin ? nonskin->logDensity(c.r, c.g) : 0.0);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, psfs::ChannelOrder>> files;
  psfs::ChannelOrder order = psfs::ChannelOrder::BGR;
  int skin_label = 1;
  std::string out;
  psfs::GmmTrainingOptions opt;
  double holdout = psfs::kDefaultHoldoutFraction;
  unsigned long long split_seed = psfs::kDefaultSplitSeed;
  int nonskin_k = 0;
  std::string note;
  std::ostringstream cmdline;
  cmdline << "train_skin_model";
  for (int i = 1; i < argc; ++i) cmdline << " " << argv[i];

  tabletop_common::CliArgs args("train_skin_model", argc, argv, usage);
  while (args.next()) {
    if (args.is("--data")) {
      files.emplace_back(args.text(), order);
    } else if (args.is("--order")) {
      const std::string o = args.text();
      if (o == "bgr") order = psfs::ChannelOrder::BGR;
      else if (o == "rgb") order = psfs::ChannelOrder::RGB;
      else args.fail("--order must be bgr or rgb, got '" + o + "'");
    } else if (args.is("--skin-label")) {
      skin_label = static_cast<int>(args.integer());
    } else if (args.is("--out")) {
      out = args.text();
    } else if (args.is("--components")) {
      opt.components = static_cast<int>(args.integer(1, 16));
    } else if (args.is("--holdout")) {
      holdout = args.number(0.0, 0.99);
    } else if (args.is("--split-seed")) {
      split_seed = static_cast<unsigned long long>(args.integer(0, std::numeric_limits<long long>::max()));
    } else if (args.is("--em-seed")) {
      opt.seed = static_cast<decltype(opt.seed)>(args.integer(0, std::numeric_limits<long long>::max()));
    } else if (args.is("--nonskin-components")) {
      nonskin_k = static_cast<int>(args.integer(0, 16));
    } else if (args.is("--note")) {
      note = args.text();
    } else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  if (files.empty()) {
    usage();
    return 2;
  }

  try {
    psfs::LabelledPixels all;
    for (const auto& f : files) all.append(psfs::loadLabelledPixels(f.first, f.second, skin_label));
    psfs::LabelledPixels train, test;
    psfs::splitHoldout(all, holdout, split_seed, &train, &test);
    std::printf("samples: %zu (%zu skin); training %zu (%zu skin), held back %zu (%zu skin)\n",
                all.size(), all.countSkin(), train.size(), train.countSkin(), test.size(),
                test.countSkin());

    const auto skin = psfs::GaussianMixture2D::train(psfs::normalizedRgOf(train, 1), opt);
    std::printf("skin GMM (%d components, normalised rg):\n", skin.size());
    for (const auto& c : skin.components())
      std::printf("  w %.4f  mean (%.4f, %.4f)  sd (%.4f, %.4f)  corr %.3f\n", c.weight, c.mean.x(),
                  c.mean.y(), std::sqrt(c.covariance(0, 0)), std::sqrt(c.covariance(1, 1)),
                  c.covariance(0, 1) / std::sqrt(c.covariance(0, 0) * c.covariance(1, 1)));

    double auc = std::nan("");
    if (test.size() > 0) {
      auc = psfs::rocAuc(skinScores(skin, nullptr, test), test.skin);
      std::printf("held-back ROC AUC, p(c|S) vs uniform (the pipeline's score): %.4f\n", auc);
      if (nonskin_k > 0) {
        psfs::GmmTrainingOptions o2 = opt;
        o2.components = nonskin_k;
        const auto nonskin = psfs::GaussianMixture2D::train(psfs::normalizedRgOf(train, 0), o2);
        std::printf(
            "held-back ROC AUC, p(c|S)/p(c|notS) with a %d-component non-skin GMM "
            "(comparison only): %.4f\n",
            nonskin_k, psfs::rocAuc(skinScores(skin, &nonskin, test), test.skin));
      }
    }

    if (!out.empty()) {
      char date[32];
      const std::time_t now = std::time(nullptr);
      std::strftime(date, sizeof(date), "%Y-%m-%d", std::gmtime(&now));
      std::ostringstream hdr;
      hdr << "Skin-colour GMM p(c|S) over normalised rg (thesis 4.2.1; psfs::GaussianMixture2D).\n"
          << "Made by: " << cmdline.str() << "\n"
          << "Data: ";
      for (std::size_t i = 0; i < files.size(); ++i)
        hdr << (i ? ", " : "") << files[i].first.substr(files[i].first.find_last_of('/') + 1)
            << (files[i].second == psfs::ChannelOrder::BGR ? " (B,G,R,label)" : " (R,G,B,label)");
      hdr << "; " << train.size() << " training samples (" << train.countSkin() << " skin), "
          << test.size() << " held back (split seed " << split_seed << ", fraction " << holdout
          << ")\n"
          << "Date: " << date << "\n";
      char aucs[96];
      std::snprintf(aucs, sizeof(aucs), "Held-back ROC AUC of p(c|S): %.4f", auc);
      hdr << aucs;
      if (!note.empty()) hdr << "\n" << note;
      skin.save(out, hdr.str());
      std::printf("wrote %s\n", out.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "train_skin_model: %s\n", e.what());
    return 1;
  }
  return 0;
}
