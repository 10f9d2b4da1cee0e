#include "sunsky.h"

#include <math.h>
#include <stdlib.h>


double sg_preetham_zenith_luminance(double turbidity, double theta_sun)
{
    double chi = (4.0 / 9.0 - turbidity / 120.0) * (M_PI - 2.0 * theta_sun);
    return (4.0453 * turbidity - 4.9710) * tan(chi) - 0.2155 * turbidity + 2.4192;
}

/* The zenith chromaticity: [T^2 T 1] M [theta^3 theta^2 theta 1]^T (the paper's appendix). */
static double zenith_chromaticity(const double m[3][4], double t, double theta)
{
    double th[4] = {theta * theta * theta, theta * theta, theta, 1.0}, tt[3] = {t * t, t, 1.0}, sum = 0.0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            sum += tt[r] * m[r][c] * th[c];
    return sum;
}

void sg_preetham_init(SgPreethamSky *sky, double turbidity, double theta_sun)
{
    static const double mx[3][4] = {{0.00166, -0.00375, 0.00209, 0.0},
                                    {-0.02903, 0.06377, -0.03202, 0.00394},
                                    {0.11693, -0.21196, 0.06052, 0.25886}};
    static const double my[3][4] = {{0.00275, -0.00610, 0.00317, 0.0},
                                    {-0.04214, 0.08970, -0.04153, 0.00516},
                                    {0.15346, -0.26756, 0.06670, 0.26688}};
    /* the Perez coefficients, linear in T: {slope, offset} for A..E */
    static const double cY[5][2] = {{0.1787, -1.4630}, {-0.3554, 0.4275}, {-0.0227, 5.3251}, {0.1206, -2.5771},
                                    {-0.0670, 0.3703}};
    static const double cx[5][2] = {{-0.0193, -0.2592}, {-0.0665, 0.0008}, {-0.0004, 0.2125}, {-0.0641, -0.8989},
                                    {-0.0033, 0.0452}};
    static const double cy[5][2] = {{-0.0167, -0.2608}, {-0.0950, 0.0092}, {-0.0079, 0.2102}, {-0.0441, -1.6537},
                                    {-0.0109, 0.0529}};
    double t = turbidity;
    sky->turbidity = t;
    sky->theta_sun = theta_sun;
    sky->zenith_Y = sg_preetham_zenith_luminance(t, theta_sun);
    sky->zenith_x = zenith_chromaticity(mx, t, theta_sun);
    sky->zenith_y = zenith_chromaticity(my, t, theta_sun);
    for (int i = 0; i < 5; i++) {
        sky->perez_Y[i] = cY[i][0] * t + cY[i][1];
        sky->perez_x[i] = cx[i][0] * t + cx[i][1];
        sky->perez_y[i] = cy[i][0] * t + cy[i][1];
    }
}

double sg_perez(const double c[5], double theta, double gamma)
{
    double cg = cos(gamma);
    return (1.0 + c[0] * exp(c[1] / cos(theta))) * (1.0 + c[2] * exp(c[3] * gamma) + c[4] * cg * cg);
}

void sg_preetham_xyY(const SgPreethamSky *sky, double theta, double gamma, double xyY[3])
{
    theta = fmin(theta, 0.5 * M_PI - 1e-3); /* 1 / cos theta stays finite at the horizon */
    double ts = sky->theta_sun;
    xyY[0] = sky->zenith_x * sg_perez(sky->perez_x, theta, gamma) / sg_perez(sky->perez_x, 0.0, ts);
    xyY[1] = sky->zenith_y * sg_perez(sky->perez_y, theta, gamma) / sg_perez(sky->perez_y, 0.0, ts);
    xyY[2] = sky->zenith_Y * sg_perez(sky->perez_Y, theta, gamma) / sg_perez(sky->perez_Y, 0.0, ts);
}

void sg_preetham_rgb(const SgPreethamSky *sky, double theta, double gamma, float rgb[3])
{
    double c[3];
    sg_preetham_xyY(sky, theta, gamma, c);
    double x = c[0], y = c[1], Y = fmax(c[2], 0.0);
    if (!(y > 1e-6)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    double X = x / y * Y, Z = fmax(1.0 - x - y, 0.0) / y * Y;
    /* XYZ to linear sRGB (D65) */
    double r = 3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z;
    double g = -0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z;
    double b = 0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z;
    rgb[0] = (float)fmax(r, 0.0);
    rgb[1] = (float)fmax(g, 0.0);
    rgb[2] = (float)fmax(b, 0.0);
}

float *sg_sky_image(const SgPreethamSky *sky, const double sun[3], int width, int height, double scale, bool extend,
                    SgError *err)
{
    float *img = width > 0 && height > 0 ? malloc(sizeof(float) * 3 * (size_t)width * height) : NULL;
    if (!img)
        return sg_fail(err, "sky image of %d x %d: out of memory", width, height), NULL;
    for (int j = 0; j < height; j++) {
        double theta = (j + 0.5) / height * M_PI; /* from +z down */
        for (int i = 0; i < width; i++) {
            double phi = (i + 0.5) / width * 2.0 * M_PI;
            double d[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
            float *px = img + 3 * ((size_t)j * width + i);
            if (d[2] <= 0.0 && !extend) {
                px[0] = px[1] = px[2] = 0.0f;
                continue;
            }
            double cg = fmin(fmax(d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2], -1.0), 1.0);
            sg_preetham_rgb(sky, theta, acos(cg), px);
            for (int c = 0; c < 3; c++)
                px[c] = (float)(px[c] * scale);
        }
    }
    return img;
}

void sg_sun_radiance(double turbidity, double theta_sun, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    double deg = theta_sun * 180.0 / M_PI;
    if (!(deg < 93.885 - 1e-3))
        return;
    /* relative optical air mass (Kasten's fit, as Preetham's sun) */
    double mass = 1.0 / (cos(theta_sun) + 0.15 * pow(93.885 - deg, -1.253));
    /* Angstrom's aerosol turbidity from Linke's T: beta = 0.04608 T - 0.04586, alpha 1.3 */
    double beta = fmax(0.04608 * turbidity - 0.04586, 0.0);
    /* the sRGB primaries' dominant wavelengths (micrometres) */
    static const double lambda[3] = {0.610, 0.550, 0.465};
    /* the sun outside the atmosphere: about 128 klx over its disk's solid angle */
    const double outside = 128.0 / (M_PI * SG_SUN_ANGULAR_RADIUS * SG_SUN_ANGULAR_RADIUS);
    for (int c = 0; c < 3; c++) {
        double rayleigh = 0.008735 * pow(lambda[c], -4.08);
        double aerosol = beta * pow(lambda[c], -1.3);
        rgb[c] = (float)(outside * exp(-mass * (rayleigh + aerosol)));
    }
}

void sg_sun_position(int year, int month, int day, double hour, double minute, double second, double timezone,
                     double latitude, double longitude, double *zenith, double *azimuth)
{
    const double rad = M_PI / 180.0;
    double hours = hour - timezone + (minute + second / 60.0) / 60.0; /* UTC */
    /* the Julian day number, then the days since J2000.0 */
    long aux1 = (month - 14) / 12;
    long aux2 = (1461L * (year + 4800 + aux1)) / 4 + (367L * (month - 2 - 12 * aux1)) / 12 -
                (3L * ((year + 4900 + aux1) / 100)) / 4 + day - 32075;
    double n = (double)aux2 - 0.5 + hours / 24.0 - 2451545.0;
    /* ecliptic coordinates */
    double omega = 2.1429 - 0.0010394594 * n;
    double mean_longitude = 4.8950630 + 0.017202791698 * n;
    double mean_anomaly = 6.2400600 + 0.0172019699 * n;
    double ecliptic_longitude = mean_longitude + 0.03341607 * sin(mean_anomaly) +
                                0.00034894 * sin(2 * mean_anomaly) - 0.0001134 - 0.0000203 * sin(omega);
    double obliquity = 0.4090928 - 6.2140e-9 * n + 0.0000396 * cos(omega);
    /* celestial coordinates */
    double sin_el = sin(ecliptic_longitude);
    double right_ascension = atan2(cos(obliquity) * sin_el, cos(ecliptic_longitude));
    if (right_ascension < 0)
        right_ascension += 2 * M_PI;
    double declination = asin(sin(obliquity) * sin_el);
    /* local coordinates */
    double gmst = 6.6974243242 + 0.0657098283 * n + hours;
    double lmst = (gmst * 15 + longitude) * rad;
    double hour_angle = lmst - right_ascension;
    double lat = latitude * rad, cos_ha = cos(hour_angle);
    double z = acos(fmin(fmax(cos(lat) * cos_ha * cos(declination) + sin(declination) * sin(lat), -1.0), 1.0));
    double az = atan2(-sin(hour_angle), tan(declination) * cos(lat) - sin(lat) * cos_ha);
    if (az < 0)
        az += 2 * M_PI;
    const double earth_radius = 6371.01, astronomical_unit = 149597890; /* km */
    *zenith = z + earth_radius / astronomical_unit * sin(z); /* parallax */
    *azimuth = az;
}
