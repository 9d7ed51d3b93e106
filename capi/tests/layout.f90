! The Fortran module's bind(c) types read what the C ABI writes: the defaults of
! abut_pair_options field by field, and a report's fields after a known increment. A field
! out of place in abut.f90 reads another field's value here. Exits non-zero on a mismatch.
!
!   gfortran -Jtarget capi/fortran/abut.f90 capi/tests/layout.f90 -Ltarget/release -labut -o layout
program layout
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
  use abut
  implicit none
  type(abut_pair_options) :: o
  type(abut_report) :: r
  type(c_ptr) :: device, model, contact
  real(c_double) :: x(3, 4), v(3, 4), f(3, 4), m(4)
  integer(c_int32_t) :: tri(3) = [0, 1, 2], slave(1) = [3], surface, set, pair
  integer :: bad = 0

  call abut_check(abut_pair_options_default(o), "options")
  call expect(o%enforcement == ABUT_ENFORCEMENT_PENALTY, "enforcement")
  call expect(o%stiffness == ABUT_STIFFNESS_AUTO, "stiffness")
  call expect(o%stiffness_scale == 1.0_c_double, "stiffness_scale")
  call expect(o%law%kind == ABUT_LAW_KIND_DEFAULT, "law%kind")
  call expect(o%law%table_points == 0, "law%table_points")
  call expect(o%damping == 0.03_c_double, "damping")
  call expect(o%friction == 0, "friction")
  call expect(ieee_is_nan(o%mu_kinetic), "mu_kinetic")
  call expect(o%stick_stiffness == 1.0_c_double, "stick_stiffness")
  call expect(o%sliding == ABUT_SLIDING_FINITE, "sliding")
  call expect(o%search_radius == 0.0_c_double, "search_radius")
  call expect(o%has_schedule == 0, "has_schedule")
  call expect(o%schedule_interval == 100, "schedule_interval")
  call expect(o%schedule_budget == 0.5_c_double, "schedule_budget")
  call expect(o%balanced == 0, "balanced")
  call expect(o%balanced_weight == 0.5_c_double, "balanced_weight")
  call expect(o%pass_weight == 1.0_c_double, "pass_weight")

  ! one slave 1e-3 into a triangle, approaching: in contact, a finite stable increment
  x = reshape([0d0, 0d0, 0d0, 1d0, 0d0, 0d0, 0d0, 1d0, 0d0, 0.2d0, 0.2d0, -1d-3], [3, 4])
  v = 0
  v(3, 4) = -1.0_c_double
  m = 1
  call abut_check(abut_device_new(ABUT_DEVICE_KIND_CPU, 0, out=device), "device")
  call abut_check(abut_model_new(3, model), "model")
  call abut_check(abut_model_add_nodes(model, x, m, 4_c_size_t), "nodes")
  call abut_check(abut_model_add_surface(model, ABUT_FACET_KIND_TRIANGLES, tri, 1_c_size_t, &
                                         surface), "surface")
  call abut_check(abut_model_add_node_set(model, slave, 1_c_size_t, id=set), "set")
  call abut_check(abut_model_add_pair(model, set, surface, o, pair), "pair")
  call abut_check(abut_contact_new(device, model, contact), "contact")
  call abut_check(abut_contact_penalty_step(contact, x, v, 4_c_size_t, 1d-3, f, &
                                            ABUT_FORCE_MODE_WRITE), "step")
  call abut_check(abut_contact_report(contact, r), "report")
  call expect(r%active == 1, "report%active")
  call expect(r%slipping == 1, "report%slipping")
  call expect(r%stable_dt > 0 .and. r%stable_dt < huge(1d0), "report%stable_dt")
  call expect(abs(r%max_overclosure - 1d-3) < 1d-9, "report%max_overclosure")
  call expect(r%fast_nodes == 0, "report%fast_nodes")
  call expect(r%fastest_node == -1, "report%fastest_node (none fast)")
  call expect(f(3, 4) > 0, "force on the slave")
  ! the slave crossing the plate at 5 lengths per increment: fast, and named
  v(3, 4) = -5000.0_c_double
  call abut_check(abut_contact_penalty_step(contact, x, v, 4_c_size_t, 1d-3, f, &
                                            ABUT_FORCE_MODE_WRITE), "step")
  call abut_check(abut_contact_report(contact, r), "report")
  call expect(r%fast_nodes == 1, "report%fast_nodes")
  call expect(r%fastest_node == 3, "report%fastest_node")
  call expect(r%fastest_pair == 0, "report%fastest_pair")
  call expect(abs(r%fastest_distance - 5d0) < 1d-9, "report%fastest_distance")
  call expect(r%fastest_radius > 0 .and. r%fastest_radius < 5, "report%fastest_radius")
  call abut_check(abut_contact_free(contact), "free")
  call abut_check(abut_model_free(model), "free")
  call abut_check(abut_device_free(device), "free")
  if (bad > 0) error stop 1
  print '(a)', "layout: the Fortran types read the C ABI's fields"

contains
  subroutine expect(ok, what)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: what
    if (.not. ok) then
      print '(a, a)', "FAIL ", what
      bad = bad + 1
    end if
  end subroutine
end program
