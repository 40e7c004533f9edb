# cmake/OpenvcuRuntimeTarget.cmake: the openvcu-runtime target (placeholder)
