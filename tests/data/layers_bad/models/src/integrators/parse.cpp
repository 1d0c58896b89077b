// A folder named like the integrators library.
