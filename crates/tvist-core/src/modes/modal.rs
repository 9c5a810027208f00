//! The modal map: modes from the link-side mass matrix and identified joint flexibility (the
//! damped eigenproblem of the flexible joints).

pub mod damped_roots;
pub mod mass_matrix_law;
pub mod modal_map;
