add_subdirectory(window)
