/* openmesh.hpp - OpenMesh's headers as the tests and benches include them (Debian libopenmesh-dev,
   link -lOpenMeshCore), and the triangle mesh type they all use. */
#ifndef TESTS_OPENMESH_HPP
#define TESTS_OPENMESH_HPP
#if defined(__GNUC__) && !defined(__clang__)
/* g++ 12 -O2 reports maybe-uninitialized inside OpenMesh's Property.hh (a vector of
   default-constructed VectorT); it is in the library's headers, not in our code */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/IO/MeshIO.hh> /* before the mesh type, as OpenMesh's docs require */
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
typedef OpenMesh::TriMesh_ArrayKernelT<> TriMesh;
#endif
