// A C interface to the parts of OpenSubdiv 3.5 that ntori is measured against and reads cages with:
// a Catmull-Clark topology refiner, its uniform refinement stencils, its limit stencils at given
// (face, s, t) locations, the CPU evaluator that applies them, and a uniformly refined mesh with its
// vertices on the limit surface (`ntori fit --cage`). Each phase is its own call so that the Rust
// side can time the factories apart from refinement. Every entry point catches C++ exceptions and
// reports failure as a null pointer or a zero return; none of them throws into Rust.

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <opensubdiv/osd/bufferDescriptor.h>
#include <opensubdiv/osd/cpuEvaluator.h>

#include <vector>

using namespace OpenSubdiv;

namespace {

struct Table {
    Far::StencilTableReal<float> const *stencils;
    Far::LimitStencilTable const *limit;  // the same object when these are limit stencils
};

}  // namespace

namespace {
void quiet_error(Far::ErrorType, const char *) {}
void quiet_warning(const char *) {}
}  // namespace

extern "C" {

// A Catmull-Clark refiner over a closed polygon mesh (`counts[f]` corners for face f, their vertex
// indices in `indices`, faces in order).
void *ntori_osd_refiner_new(int vertices, int faces, const int *counts, const int *indices) {
    // OpenSubdiv prints its errors and warnings to stdout by default, where they would mix with a
    // command's report; the calls here report failure by their results instead.
    Far::SetErrorCallback(quiet_error);
    Far::SetWarningCallback(quiet_warning);
    try {
        typedef Far::TopologyDescriptor Descriptor;
        Sdc::Options options;
        options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
        Descriptor desc;
        desc.numVertices = vertices;
        desc.numFaces = faces;
        desc.numVertsPerFace = counts;
        desc.vertIndicesPerFace = indices;
        Far::TopologyRefinerFactory<Descriptor>::Options create(Sdc::SCHEME_CATMARK, options);
        return Far::TopologyRefinerFactory<Descriptor>::Create(desc, create);
    } catch (...) {
        return nullptr;
    }
}

void ntori_osd_refiner_free(void *refiner) {
    delete static_cast<Far::TopologyRefiner *>(refiner);
}

// Uniform refinement to `level`; returns the number of vertices at that level, 0 on failure.
int ntori_osd_refine_uniform(void *refiner, int level) {
    try {
        Far::TopologyRefiner *r = static_cast<Far::TopologyRefiner *>(refiner);
        Far::TopologyRefiner::UniformOptions options(level);
        options.fullTopologyInLastLevel = false;
        r->RefineUniform(options);
        return r->GetLevel(level).GetNumVertices();
    } catch (...) {
        return 0;
    }
}

// Adaptive refinement (feature isolation) to `level`, as limit stencils need; 1 on success.
int ntori_osd_refine_adaptive(void *refiner, int level) {
    try {
        Far::TopologyRefiner *r = static_cast<Far::TopologyRefiner *>(refiner);
        r->RefineAdaptive(Far::TopologyRefiner::AdaptiveOptions(level));
        return 1;
    } catch (...) {
        return 0;
    }
}

// The stencils of the finest uniform level's vertices, in terms of the base mesh's vertices.
void *ntori_osd_uniform_stencils(const void *refiner) {
    try {
        Far::TopologyRefiner const *r = static_cast<Far::TopologyRefiner const *>(refiner);
        Far::StencilTableFactory::Options options;
        options.generateIntermediateLevels = false;
        options.generateOffsets = true;
        Table *t = new Table;
        t->stencils = Far::StencilTableFactory::Create(*r, options);
        t->limit = nullptr;
        return t;
    } catch (...) {
        return nullptr;
    }
}

// Limit stencils (with first derivatives when `derivatives` is non-zero) at `count` locations:
// ptex face `faces[k]`, parameters (s[k], t[k]). Locations of one face must be consecutive.
void *ntori_osd_limit_stencils(const void *refiner, int count, const int *faces, const float *s,
                               const float *t, int derivatives) {
    try {
        Far::TopologyRefiner const *r = static_cast<Far::TopologyRefiner const *>(refiner);
        Far::LimitStencilTableFactory::LocationArrayVec locations;
        for (int k = 0; k < count;) {
            int end = k;
            while (end < count && faces[end] == faces[k]) ++end;
            Far::LimitStencilTableFactory::LocationArray run;
            run.ptexIdx = faces[k];
            run.numLocations = end - k;
            run.s = s + k;
            run.t = t + k;
            locations.push_back(run);
            k = end;
        }
        Far::LimitStencilTableFactory::Options options;
        options.generate1stDerivatives = derivatives != 0;
        Far::LimitStencilTable const *limit =
            Far::LimitStencilTableFactory::Create(*r, locations, nullptr, nullptr, options);
        if (!limit) return nullptr;
        Table *table = new Table;
        table->stencils = limit;
        table->limit = limit;
        return table;
    } catch (...) {
        return nullptr;
    }
}

void ntori_osd_stencils_free(void *table) {
    Table *t = static_cast<Table *>(table);
    if (t) delete t->stencils;
    delete t;
}

int ntori_osd_stencil_count(const void *table) {
    return static_cast<Table const *>(table)->stencils->GetNumStencils();
}

long ntori_osd_weight_count(const void *table) {
    return static_cast<long>(static_cast<Table const *>(table)->stencils->GetWeights().size());
}

// dst[3 i ..] = stencil i applied to the float3 points `src`, for i in [start, end); 1 on success.
int ntori_osd_apply(const void *table, const float *src, float *dst, int start, int end) {
    Far::StencilTableReal<float> const *st = static_cast<Table const *>(table)->stencils;
    Osd::BufferDescriptor desc(0, 3, 3);
    return Osd::CpuEvaluator::EvalStencils(src, desc, dst, desc, &st->GetSizes()[0],
                                           &st->GetOffsets()[0], &st->GetControlIndices()[0],
                                           &st->GetWeights()[0], start, end)
               ? 1
               : 0;
}

// ntori_osd_apply on float4 points (x, y, z, w): the CPU evaluator's SIMD kernel for 4-float data.
int ntori_osd_apply4(const void *table, const float *src, float *dst, int start, int end) {
    Far::StencilTableReal<float> const *st = static_cast<Table const *>(table)->stencils;
    Osd::BufferDescriptor desc(0, 4, 4);
    return Osd::CpuEvaluator::EvalStencils(src, desc, dst, desc, &st->GetSizes()[0],
                                           &st->GetOffsets()[0], &st->GetControlIndices()[0],
                                           &st->GetWeights()[0], start, end)
               ? 1
               : 0;
}

namespace {
// A float3 primvar for Far's templated UpdateValues (inlined here, compiled with the shim).
struct Point {
    float p[3];
    void Clear() { p[0] = p[1] = p[2] = 0.0f; }
    void AddWithWeight(Point const &src, float w) {
        p[0] += w * src.p[0];
        p[1] += w * src.p[1];
        p[2] += w * src.p[2];
    }
};
}  // namespace

// The same as ntori_osd_apply through Far's own StencilTable::UpdateValues template.
void ntori_osd_update_values(const void *table, const float *src, float *dst) {
    Far::StencilTableReal<float> const *st = static_cast<Table const *>(table)->stencils;
    st->UpdateValues(reinterpret_cast<Point const *>(src), reinterpret_cast<Point *>(dst));
}

// As ntori_osd_apply, with the first derivatives into du and dv (limit stencils made with them).
int ntori_osd_apply_with_derivatives(const void *table, const float *src, float *dst, float *du,
                                     float *dv, int start, int end) {
    Far::LimitStencilTable const *st = static_cast<Table const *>(table)->limit;
    if (!st || st->GetDuWeights().empty()) return 0;
    Osd::BufferDescriptor desc(0, 3, 3);
    return Osd::CpuEvaluator::EvalStencils(src, desc, dst, desc, du, desc, dv, desc,
                                           &st->GetSizes()[0], &st->GetOffsets()[0],
                                           &st->GetControlIndices()[0], &st->GetWeights()[0],
                                           &st->GetDuWeights()[0], &st->GetDvWeights()[0], start,
                                           end)
               ? 1
               : 0;
}

namespace {
// A double-precision position for Far's PrimvarRefiner (interpolation and limit) templates.
struct Point64 {
    double p[3];
    void Clear(void * = nullptr) { p[0] = p[1] = p[2] = 0.0; }
    void AddWithWeight(Point64 const &src, double w) {
        p[0] += w * src.p[0];
        p[1] += w * src.p[1];
        p[2] += w * src.p[2];
    }
};
}  // namespace

// Uniform refinement to `level` keeping the finest level's whole topology (its faces, and the
// neighbourhoods the limit masks need); returns that level's vertex count, 0 on failure or when
// the refiner was refined before (OpenSubdiv would then keep its earlier levels).
int ntori_osd_refine_uniform_full(void *refiner, int level) {
    try {
        Far::TopologyRefiner *r = static_cast<Far::TopologyRefiner *>(refiner);
        if (level < 1 || r->GetMaxLevel() != 0) return 0;
        Far::TopologyRefiner::UniformOptions options(level);
        options.fullTopologyInLastLevel = true;
        r->RefineUniform(options);
        if (!r->IsUniform() || r->GetMaxLevel() != level) return 0;
        return r->GetLevel(level).GetNumVertices();
    } catch (...) {
        return 0;
    }
}

// The finest level's face count and the total of their corners, into `faces` and `corners`.
void ntori_osd_finest_sizes(const void *refiner, int *faces, int *corners) {
    Far::TopologyRefiner const *r = static_cast<Far::TopologyRefiner const *>(refiner);
    Far::TopologyLevel const &level = r->GetLevel(r->GetMaxLevel());
    *faces = level.GetNumFaces();
    *corners = level.GetNumFaceVertices();
}

// The finest level's faces: `counts[f]` corners for face f, their vertex indices in `indices`.
// 1 on success, 0 if the arrays (`faces` and `corners` long) do not match the level.
int ntori_osd_finest_faces(const void *refiner, int *counts, int faces, int *indices, int corners) {
    Far::TopologyRefiner const *r = static_cast<Far::TopologyRefiner const *>(refiner);
    Far::TopologyLevel const &level = r->GetLevel(r->GetMaxLevel());
    if (level.GetNumFaces() != faces || level.GetNumFaceVertices() != corners) return 0;
    int k = 0;
    for (int f = 0; f < faces; ++f) {
        Far::ConstIndexArray face = level.GetFaceVertices(f);
        if (k + face.size() > corners) return 0;
        counts[f] = face.size();
        for (int c = 0; c < face.size(); ++c) indices[k++] = face[c];
    }
    return 1;
}

// The limit positions of the finest level's vertices (after ntori_osd_refine_uniform_full), from
// the base mesh's `base_count` positions (x, y, z each): interpolated level by level, then taken
// to the limit, with two limit tangents per vertex into `du` and `dv` (each, like `out`,
// `out_count` points). 1 on success, 0 if the counts do not match the refiner's levels or it was
// not refined uniformly.
int ntori_osd_limit_positions(const void *refiner, const double *base, int base_count, double *out,
                              double *du, double *dv, int out_count) {
    try {
        Far::TopologyRefiner const *r = static_cast<Far::TopologyRefiner const *>(refiner);
        if (!r->IsUniform() || r->GetMaxLevel() < 1 ||
            r->GetLevel(0).GetNumVertices() != base_count ||
            r->GetLevel(r->GetMaxLevel()).GetNumVertices() != out_count)
            return 0;
        // Weights in double too, so the limit points carry no float rounding.
        Far::PrimvarRefinerReal<double> primvar(*r);
        int levels = r->GetMaxLevel();
        std::vector<Point64> src(r->GetLevel(0).GetNumVertices());
        for (size_t v = 0; v < src.size(); ++v)
            for (int i = 0; i < 3; ++i) src[v].p[i] = base[3 * v + i];
        for (int level = 1; level <= levels; ++level) {
            std::vector<Point64> dst(r->GetLevel(level).GetNumVertices());
            Point64 const *from = src.data();
            Point64 *to = dst.data();
            primvar.Interpolate(level, from, to);
            src.swap(dst);
        }
        Point64 *limit = reinterpret_cast<Point64 *>(out);
        Point64 *tan1 = reinterpret_cast<Point64 *>(du);
        Point64 *tan2 = reinterpret_cast<Point64 *>(dv);
        Point64 const *finest = src.data();
        primvar.Limit(finest, limit, tan1, tan2);
        return 1;
    } catch (...) {
        return 0;
    }
}

}  // extern "C"
