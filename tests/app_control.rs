//! The Control view on the bundled sample project: the operating points of the model shown, a row
//! click choosing the point whose Bode is drawn, and the points following a change of the model.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::app::harness;
use crate::common::sample;
use egui_kittest::kittest::Queryable;
use jetid::core::control::PointSource;
use jetid::ui::{App, Command, Session, Tab};

#[test]
fn the_control_view_schedules_the_model_and_follows_it() {
    let mut app = App::new(Session::default());
    app.apply(Command::OpenProject(sample("sr30/project.toml")));
    assert!(app.view.errors.is_empty(), "{:?}", app.view.errors);
    app.apply(Command::SelectOutput("thrust_n".into()));
    app.apply(Command::ShowTab(Tab::Control));
    app.settle();
    let mut harness = harness(app);
    harness.run();
    let points = harness.state().view.views.control.points().expect("operating points").to_vec();
    assert_eq!(points.iter().filter(|p| p.source == PointSource::Grid).count(), 9);
    assert!(
        points.iter().any(|p| matches!(&p.source, PointSource::SteadyRun(_))),
        "the sample's steady run gives a plateau point"
    );
    // The table shows every row, the steady run's plateau (the last) inside the window, with the
    // units of u* and of the local gain, the output's per the input's.
    let plateau = harness.get_by_label("steady: steady").rect();
    assert!(plateau.bottom() < 900.0 - 20.0, "the plateau's row lies below the fold: {plateau:?}");
    harness.get_by_label("u* [gal/h]");
    harness.get_by_label("dy/du [N/(gal/h)]");
    assert_eq!(
        jetid::ui::views::control::gain_legend(2.5, &jetid::io::report::markdown::gain_unit("rpm", "gal/h")),
        "local gain dy/du (largest 2.5000e0 rpm/(gal/h))"
    );
    assert!(jetid::io::report::markdown::gain_unit("rpm", "").ends_with("per input unit"));
    // Thrust grows faster than linearly with fuel flow: the local gain rises along the range.
    assert!(points[8].gain > points[0].gain, "{} vs {}", points[8].gain, points[0].gain);
    harness.get_by_label("grid 5").click();
    harness.run();
    assert_eq!(harness.state().view.views.control.selected, 4);
    // A linear static map makes the gain the same everywhere: the view follows the model. (On the
    // speed: thrust with a linear map of its own is no longer its own model but read off the
    // speed's, whose validation runs prefer it.)
    let speed = "shaft_speed_rpm";
    let settings =
        harness.state().cache.output(speed).expect("the speed is identified").setup.settings.clone();
    let linear = jetid::core::identification::settings::OutputSettings { static_order: Some(1), ..settings };
    harness.state_mut().apply(Command::SelectOutput(speed.into()));
    harness.state_mut().apply(Command::SetOutputSettings { output: speed.into(), settings: linear });
    harness.state_mut().settle();
    harness.run();
    let after = harness.state().view.views.control.points().expect("operating points").to_vec();
    assert!(
        (after[0].gain - after[8].gain).abs() <= 1e-9 * after[0].gain.abs(),
        "{} vs {}",
        after[0].gain,
        after[8].gain
    );
}
