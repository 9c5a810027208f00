//! What a constructed shaper reports about itself: its channel count and control period are
//! those of its configuration, whatever the number of modes.

use core::f64::consts::PI;
use tvist_core::{ConstantModes, Mode, ShaperKind, TvShaper, TvShaperConfig};

#[test]
fn tv_shaper_reports_its_configuration() {
    for (n_dof, dt_s) in [(1, 0.002), (6, 0.008), (7, 0.001)] {
        let modes = vec![
            Mode::new(2.0 * PI * 8.0, 0.1),
            Mode::new(2.0 * PI * 5.0, 0.2),
        ];
        let config = TvShaperConfig::new(dt_s, n_dof, ShaperKind::Zv);
        let shaper = TvShaper::new(ConstantModes::new(modes).expect("valid"), &config)
            .expect("valid configuration");
        assert_eq!(shaper.n_dof(), n_dof);
        assert_eq!(shaper.dt_s(), dt_s);
        assert_eq!(shaper.current_modes().len(), 2);
    }
}
