// The translation unit of the precompiled headers' hosts
// (cmake/PrecompiledHeaders.cmake): its headers are all they compile.
