! S1002 wheel points stored as in the Manchester contact benchmark file MBench_S1002_v3.prw
! (published with the CONTACT software of Vtech CMCC): column 1 toward the flange, column 2 the
! radius increase, both mm; mirror.y = 1 and inversion = 1 as in that file. Values verbatim.
  header.begin
    version = 1
    type    = 1      ! wheel
  header.end
  spline.begin
    comment   = 'S1002 subset, mirrored'
    mirror.y  = 1
    mirror.z  = 0
    inversion = 1
    units.len.f = +1.000000000000000e+03
    units.ang.f = +1.000000000000000e+00
    point.begin
-6.0000000E+01	-2.6356764E+00
-4.5008704E+01	-1.6362567E+00
-1.4239919E+01	-2.4892741E-01
3.4825167E-01	1.1887234E-02
2.5580201E+01	2.6414043E+00
3.8335925E+01	1.1757921E+01
5.4892493E+01	2.7999518E+01
6.9612628E+01	1.3485642E+01
    point.end
  spline.end
