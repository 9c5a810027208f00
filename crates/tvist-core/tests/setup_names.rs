//! Setup-time names: each registry name selects its variant, an unknown name is refused.

use tvist_core::{Discretization, Error, Interpolation};

#[test]
fn interpolation_names_select_their_stencil() {
    assert_eq!(
        Interpolation::from_name("linear"),
        Ok(Interpolation::Linear)
    );
    assert_eq!(Interpolation::from_name("cubic"), Ok(Interpolation::Cubic));
    for bad in ["Cubic", "lagrange", ""] {
        assert!(
            matches!(Interpolation::from_name(bad), Err(Error::UnknownInterpolation(ref n)) if n == bad),
            "{bad:?}"
        );
    }
}

#[test]
fn discretization_names_select_their_method() {
    for (name, kind) in [
        ("matched", Discretization::Matched),
        ("tustin", Discretization::Tustin),
    ] {
        assert_eq!(Discretization::from_name(name), Ok(kind));
        assert_eq!(kind.name(), name);
    }
    for bad in ["zoh", "Tustin", ""] {
        assert!(Discretization::from_name(bad).is_err(), "{bad:?}");
    }
}
