//! The example models in `assets/models/` are what the code makes: each is fitted again with the
//! parameters assets/README.md gives and compared point by point, and each loads, exports and
//! describes a closed surface of its genus.

use crate::common::{SMALL_MODEL_GENERA, asset, small_model, small_model_fit};

#[test]
fn example_models_are_what_the_fit_makes() {
    for genus in SMALL_MODEL_GENERA {
        let stored = small_model(genus);
        let fitted = small_model_fit(genus);
        assert_eq!(stored.genus(), genus);
        assert_eq!(stored.settings(), fitted.settings(), "genus {genus}");
        let size = fitted.control_net_size();
        let worst = stored
            .control_points()
            .iter()
            .zip(fitted.control_points())
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        // The fit is deterministic; the margin allows for another CPU's libm.
        assert!(
            worst <= 1e-9 * size,
            "assets/models/genus-{genus}.json is stale (off by {worst:e} of {size}): \
             regenerate it as assets/README.md says"
        );
    }
}

#[test]
fn every_asset_is_listed_in_the_assets_readme() {
    let readme = std::fs::read_to_string(asset("README.md")).unwrap();
    for entry in std::fs::read_dir(asset("models")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(
            readme.contains(&format!("`{name}`")),
            "{name} is not described in assets/README.md"
        );
    }
}
