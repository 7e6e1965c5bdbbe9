// Hand meshing timings: our marching cubes (probabilistic and binary) against VTK's
// vtkFlyingEdges3D and vtkMarchingCubes on the same bytes and the same iso level (153.5), with
// and without normals. Workloads (test/synthetic_volumes.h): two 83^3 hand sub-volumes (the
// per-frame case, DESIGN.md section 4), and person-like volumes at 128x128x96 and 256x256x192.
// Counters: triangles and vertices per iteration (summed over the volumes of the workload).
// VTK runs on its own SMP backend (TBB in Debian's build): vtkFlyingEdges3D on 2 threads and
// on 1; vtkMarchingCubes is single-threaded.
//
//   bench_meshing --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkMarchingCubes.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSMPTools.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include <memory>
#include <vector>

#include "../test/synthetic_volumes.h"
#include "cvephands_bridge/mesh/marching_cubes.h"

namespace {

using cvephands_test::TestVolume;

enum Workload { kTwoHands = 0, kPerson128 = 1, kPerson256 = 2 };

const std::vector<TestVolume>& volumes(int w) {
  static std::vector<TestVolume> sets[3];
  if (sets[w].empty()) {
    if (w == kTwoHands) {
      sets[w].push_back(cvephands_test::handVolume(1));
      sets[w].push_back(cvephands_test::handVolume(2, true));
    } else if (w == kPerson128) {
      sets[w].push_back(cvephands_test::personVolume(Eigen::Vector3i(128, 128, 96), 3));
    } else {
      sets[w].push_back(cvephands_test::personVolume(Eigen::Vector3i(256, 256, 192), 4));
    }
  }
  return sets[w];
}

const char* workloadName(int w) {
  return w == kTwoHands ? "2 hands 83^3" : w == kPerson128 ? "person 128x128x96" : "person 256x256x192";
}

// args: workload, mode (0 probabilistic, 1 binary), normals, threads
void BM_Ours(benchmark::State& st) {
  const auto& vols = volumes(static_cast<int>(st.range(0)));
  cvephands::MarchingCubesOptions o;
  o.mode = st.range(1) ? cvephands::MeshingMode::kBinary : cvephands::MeshingMode::kProbabilistic;
  o.compute_normals = st.range(2) != 0;
  o.threads = static_cast<int>(st.range(3));
  // One meshing object and one output mesh per stream, reused every frame as the pipeline does.
  std::vector<cvephands::MarchingCubes> mc(vols.size(), cvephands::MarchingCubes(o));
  std::vector<cvephands::TriangleMesh> out(vols.size());
  for (auto _ : st)
    for (size_t i = 0; i < vols.size(); ++i) {
      mc[i].extract(vols[i].view(), &out[i]);
      benchmark::DoNotOptimize(out[i].triangles.data());
    }
  size_t tris = 0, verts = 0;
  for (const auto& m : out) tris += m.numTriangles(), verts += m.numVertices();
  st.counters["triangles"] = double(tris);
  st.counters["vertices"] = double(verts);
  st.SetLabel(std::string(workloadName(int(st.range(0)))) + (st.range(1) ? ", binary" : ", probabilistic") +
              (st.range(2) ? ", normals" : ", no normals"));
}

// VTK samples at points: the image's origin is the first voxel centre.
vtkSmartPointer<vtkImageData> vtkImage(const TestVolume& v) {
  auto scalars = vtkSmartPointer<vtkUnsignedCharArray>::New();
  scalars->SetArray(const_cast<uint8_t*>(v.data.data()), static_cast<vtkIdType>(v.data.size()),
                    1 /* do not free: the volume owns the bytes */);
  scalars->SetName("p");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(v.dims.x(), v.dims.y(), v.dims.z());
  image->SetSpacing(v.voxel, v.voxel, v.voxel);
  image->SetOrigin(v.origin.x() + 0.5 * v.voxel, v.origin.y() + 0.5 * v.voxel,
                   v.origin.z() + 0.5 * v.voxel);
  image->GetPointData()->SetScalars(scalars);
  return image;
}

// args: workload, normals, threads (vtkSMPTools::Initialize; explicit, since a later
// Initialize(0) does not bring back the default once a count was set)
template <typename Filter>
void BM_Vtk(benchmark::State& st) {
  const auto& vols = volumes(static_cast<int>(st.range(0)));
  vtkSMPTools::Initialize(static_cast<int>(st.range(2)));
  std::vector<vtkSmartPointer<vtkImageData>> images;
  std::vector<vtkSmartPointer<Filter>> filters;
  for (const auto& v : vols) {
    images.push_back(vtkImage(v));
    auto f = vtkSmartPointer<Filter>::New();
    f->SetInputData(images.back());
    f->SetValue(0, 153.5);
    f->SetComputeNormals(st.range(1) != 0);
    f->SetComputeGradients(0);
    f->SetComputeScalars(0);
    filters.push_back(f);
  }
  for (auto _ : st)
    for (auto& f : filters) {
      f->Modified();  // re-run on the same input, as a new frame would
      f->Update();
      benchmark::DoNotOptimize(f->GetOutput());
    }
  double tris = 0, verts = 0;
  for (auto& f : filters) {
    tris += double(f->GetOutput()->GetNumberOfPolys());
    verts += double(f->GetOutput()->GetNumberOfPoints());
  }
  st.counters["triangles"] = tris;
  st.counters["vertices"] = verts;
  st.SetLabel(std::string(workloadName(int(st.range(0)))) + (st.range(1) ? ", normals" : ", no normals") +
              ", VTK SMP " + vtkSMPTools::GetBackend() + " " +
              std::to_string(vtkSMPTools::GetEstimatedNumberOfThreads()) + " threads");
}

void oursArgs(benchmark::internal::Benchmark* b) {
  for (int w = 0; w < 3; ++w) {
    b->Args({w, 0, 1, 2});  // the pipeline's case
    b->Args({w, 0, 1, 1});
    b->Args({w, 0, 0, 2});
    b->Args({w, 1, 1, 2});
  }
}
void flyingEdgesArgs(benchmark::internal::Benchmark* b) {
  for (int w = 0; w < 3; ++w) {
    b->Args({w, 1, 2});
    b->Args({w, 1, 1});
    b->Args({w, 0, 2});
  }
}
void marchingCubesArgs(benchmark::internal::Benchmark* b) {  // single-threaded filter
  for (int w = 0; w < 3; ++w) {
    b->Args({w, 1, 1});
    b->Args({w, 0, 1});
  }
}

BENCHMARK(BM_Ours)->Apply(oursArgs)->ArgNames({"work", "binary", "normals", "threads"})
    ->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK_TEMPLATE(BM_Vtk, vtkFlyingEdges3D)->Apply(flyingEdgesArgs)
    ->ArgNames({"work", "normals", "threads"})->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK_TEMPLATE(BM_Vtk, vtkMarchingCubes)->Apply(marchingCubesArgs)
    ->ArgNames({"work", "normals", "threads"})->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
