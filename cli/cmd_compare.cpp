// gtn compare A.png B.png [--json]: the paper's image difference (section 6.3): RMSE over the pixels
// that are not background (black) in both images, on the 0-255 scale, PSNR and the largest
// difference.
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "render/image.h"

namespace gtn::cli {

namespace {
struct CompareArgs {
  std::string a, b;
  bool json = false;
};

int runCompare(const CompareArgs& args) {
  auto a = readPng(args.a);
  if (!a.isOk()) return reportError(a.status());
  auto b = readPng(args.b);
  if (!b.isOk()) return reportError(b.status());
  auto d = compareImages(a.value(), b.value());
  if (!d.isOk()) return reportError(Status(d.status().code(), args.a + ", " + args.b + ": " + d.status().message()));
  if (args.json) {
    nlohmann::json j;
    j["a"] = args.a;
    j["b"] = args.b;
    j["width"] = a->width;
    j["height"] = a->height;
    j["pixels_compared"] = d->pixels;
    j["rmse"] = d->rmse;
    j["psnr"] = std::isinf(d->psnr) ? nlohmann::json(nullptr) : nlohmann::json(d->psnr);
    j["max_difference"] = d->max_difference;
    std::printf("%s\n", jsonText(j).c_str());
  } else {
    std::printf("pixels compared  %llu of %d%s\n", static_cast<unsigned long long>(d->pixels), a->width * a->height,
                d->pixels == 0 ? " (both images are all background: nothing to compare)" : "");
    std::printf("rmse             %.4f\n", d->rmse);
    if (std::isinf(d->psnr)) std::printf("psnr             inf\n");
    else std::printf("psnr             %.2f dB\n", d->psnr);
    std::printf("max difference   %d\n", d->max_difference);
  }
  return 0;
}
}  // namespace

Command addCompareCommand(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* sub = app.add_subcommand(
      "compare", "Compare two images: RMSE over non-background pixels (0-255), PSNR, largest difference");
  sub->add_option("a", args->a, "first PNG image")->required();
  sub->add_option("b", args->b, "second PNG image")->required();
  sub->add_flag("--json", args->json, "write one JSON document to standard output");
  return {sub, [args] { return runCompare(*args); }};
}

}  // namespace gtn::cli
