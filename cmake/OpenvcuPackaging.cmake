# cmake/OpenvcuPackaging.cmake: install layout and CPack (placeholder)
