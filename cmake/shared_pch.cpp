// The translation unit hystbench_pch compiles its precompiled header with (cmake/shared_pch.cmake).
