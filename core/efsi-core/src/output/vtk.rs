//! VTK XML RectilinearGrid (`.vtr`) and ParaView collection (`.pvd`) writers.
