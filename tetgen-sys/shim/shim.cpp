// Minimal extern "C" shim around TetGen 1.5's C++ library interface.
//
// Written for dsc-seg; contains no TetGen source. TetGen is only used through
// its public header and linked from the system library (libtet).
//
// Memory rules: `tetgenio`'s destructor `delete[]`s every list it points to,
// so every input array is allocated here with `new[]` and handed over to the
// input `tetgenio`. The output `tetgenio` lives on the heap inside an opaque
// handle until the caller has copied what it needs and frees the handle.
//
// Error rules: no C++ exception may cross the C boundary. TetGen reports
// errors by throwing an `int` (see `terminatetetgen`); we catch everything and
// return an error code instead.

#ifndef TETLIBRARY
#define TETLIBRARY
#endif
#include <tetgen.h>

#include <cstring>
#include <new>
#include <vector>

extern "C" {

// Result codes (kept in sync with src/lib.rs).
//   0            success
//   1..=10       the int thrown by TetGen (1 out of memory, 2 internal error,
//                3 self-intersection, 4 small feature size, 5 close facets,
//                10 input error)
//   TG_ERR_ARGS  invalid argument to the shim
//   TG_ERR_ALLOC std::bad_alloc
//   TG_ERR_STD   other std::exception
//   TG_ERR_OTHER any other exception
enum {
  TG_OK = 0,
  TG_ERR_ARGS = -1,
  TG_ERR_ALLOC = -2,
  TG_ERR_STD = -3,
  TG_ERR_OTHER = -4,
};

struct tg_output {
  tetgenio io;
};

// Builds a PLC from `npoints` points (3 doubles each), `ntris` triangles
// (3 zero-based ints each) and `nregions` regions (5 doubles each: seed x, y,
// z, attribute, max volume), runs `tetrahedralize(switches, ...)` and on
// success stores a newly allocated output handle in `*out`.
int tg_tetrahedralize(const char *switches, int npoints, const double *points,
                      int ntris, const int *tris, int nregions,
                      const double *regions, tg_output **out) {
  if (out == nullptr) {
    return TG_ERR_ARGS;
  }
  *out = nullptr;
  if (switches == nullptr || npoints < 0 || ntris < 0 || nregions < 0 ||
      (npoints > 0 && points == nullptr) || (ntris > 0 && tris == nullptr) ||
      (nregions > 0 && regions == nullptr)) {
    return TG_ERR_ARGS;
  }
  tg_output *result = nullptr;
  try {
    tetgenio in;
    in.firstnumber = 0;

    in.numberofpoints = npoints;
    in.pointlist = new REAL[3 * static_cast<size_t>(npoints)];
    for (size_t i = 0; i < 3 * static_cast<size_t>(npoints); ++i) {
      in.pointlist[i] = points[i];
    }

    // Allocate the facet array and immediately record its length, so that the
    // destructor frees exactly what has been allocated even if a later `new`
    // throws: polygon lists start out null with zero polygons.
    in.facetlist = new tetgenio::facet[ntris];
    for (int i = 0; i < ntris; ++i) {
      tetgenio::facet &f = in.facetlist[i];
      f.polygonlist = nullptr;
      f.numberofpolygons = 0;
      f.holelist = nullptr;
      f.numberofholes = 0;
    }
    in.numberoffacets = ntris;
    for (int i = 0; i < ntris; ++i) {
      tetgenio::facet &f = in.facetlist[i];
      f.polygonlist = new tetgenio::polygon[1];
      f.polygonlist[0].vertexlist = nullptr;
      f.polygonlist[0].numberofvertices = 0;
      f.numberofpolygons = 1;
      tetgenio::polygon &p = f.polygonlist[0];
      p.vertexlist = new int[3];
      p.numberofvertices = 3;
      for (int k = 0; k < 3; ++k) {
        p.vertexlist[k] = tris[3 * static_cast<size_t>(i) + k];
      }
    }

    if (nregions > 0) {
      in.regionlist = new REAL[5 * static_cast<size_t>(nregions)];
      in.numberofregions = nregions;
      for (size_t i = 0; i < 5 * static_cast<size_t>(nregions); ++i) {
        in.regionlist[i] = regions[i];
      }
    }

    // `tetrahedralize` takes a mutable C string.
    std::vector<char> sw(switches, switches + std::strlen(switches) + 1);

    result = new tg_output();
    tetrahedralize(sw.data(), &in, &result->io);
    *out = result;
    return TG_OK;
  } catch (int code) {
    delete result;
    return code == 0 ? TG_ERR_OTHER : code;
  } catch (const std::bad_alloc &) {
    delete result;
    return TG_ERR_ALLOC;
  } catch (const std::exception &) {
    delete result;
    return TG_ERR_STD;
  } catch (...) {
    delete result;
    return TG_ERR_OTHER;
  }
}

// Frees an output handle (null is allowed).
void tg_output_free(tg_output *out) { delete out; }

// Index of the first point in the output (0 when `z` was given).
int tg_output_firstnumber(const tg_output *out) { return out->io.firstnumber; }

int tg_output_num_points(const tg_output *out) {
  return out->io.pointlist ? out->io.numberofpoints : 0;
}

int tg_output_num_tets(const tg_output *out) {
  return out->io.tetrahedronlist ? out->io.numberoftetrahedra : 0;
}

int tg_output_num_corners(const tg_output *out) {
  return out->io.numberofcorners;
}

int tg_output_num_tet_attributes(const tg_output *out) {
  return out->io.tetrahedronattributelist
             ? out->io.numberoftetrahedronattributes
             : 0;
}

// Copies 3 * num_points doubles into `buf`.
void tg_output_copy_points(const tg_output *out, double *buf) {
  const size_t n = 3 * static_cast<size_t>(tg_output_num_points(out));
  if (n > 0) {
    std::memcpy(buf, out->io.pointlist, n * sizeof(double));
  }
}

// Copies num_corners * num_tets ints into `buf`.
void tg_output_copy_tets(const tg_output *out, int *buf) {
  const size_t n = static_cast<size_t>(tg_output_num_corners(out)) *
                   static_cast<size_t>(tg_output_num_tets(out));
  if (n > 0) {
    std::memcpy(buf, out->io.tetrahedronlist, n * sizeof(int));
  }
}

// Copies num_tet_attributes * num_tets doubles into `buf`.
void tg_output_copy_tet_attributes(const tg_output *out, double *buf) {
  const size_t n = static_cast<size_t>(tg_output_num_tet_attributes(out)) *
                   static_cast<size_t>(tg_output_num_tets(out));
  if (n > 0) {
    std::memcpy(buf, out->io.tetrahedronattributelist, n * sizeof(double));
  }
}

}  // extern "C"
